# roadsplat - see `make help`.
#
# Build outputs go to $(BUILD) (default build/). Sanitizer builds use their own
# folders (build/asan), so they never mix objects with the normal build.

VERSION_MAJOR := 0
VERSION_MINOR := 1
VERSION_PATCH := 0
VERSION       := $(VERSION_MAJOR).$(VERSION_MINOR).$(VERSION_PATCH)

PREFIX  ?= /usr/local
DESTDIR ?=
BINDIR  ?= $(PREFIX)/bin
LIBDIR  ?= $(PREFIX)/lib
INCDIR  ?= $(PREFIX)/include
MANDIR  ?= $(PREFIX)/share/man
PKGCONFIGDIR ?= $(LIBDIR)/pkgconfig

BUILD   ?= build
CC      ?= cc
CXX     ?= c++
OPT     ?= -O2 -g
# No -ffast-math anywhere: it removes the NaN checks the library relies on.
WARN    := -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wvla
CFLAGS  ?=
SAN     ?=
ALL_CFLAGS := -std=c99 $(OPT) $(WARN) $(SAN) -Iinclude -fvisibility=hidden -fPIC $(CFLAGS)
LDLIBS_CORE := -lm

PKG_CONFIG ?= pkg-config
OIIO_CFLAGS = $(shell $(PKG_CONFIG) --cflags OpenImageIO 2>/dev/null)
OIIO_LIBS   = $(shell $(PKG_CONFIG) --libs OpenImageIO 2>/dev/null)

# Optional OSMesa renderer: auto-detected, or forced with WITH_OSMESA=1/0.
WITH_OSMESA ?= $(shell $(PKG_CONFIG) --exists osmesa 2>/dev/null && echo 1 || echo 0)
ifeq ($(WITH_OSMESA),1)
OSMESA_CFLAGS = -DRS_WITH_OSMESA $(shell $(PKG_CONFIG) --cflags osmesa 2>/dev/null)
OSMESA_LIBS   = $(or $(shell $(PKG_CONFIG) --libs osmesa 2>/dev/null),-lOSMesa)
endif

LIB_SRC   := $(sort $(wildcard lib/*.c))
LIB_OBJ   := $(LIB_SRC:%.c=$(BUILD)/%.o)
CLI_CSRC  := $(sort $(wildcard cli/*.c))
CLI_XSRC  := $(sort $(wildcard cli/*.cpp))
CLI_OBJ   := $(CLI_CSRC:%.c=$(BUILD)/%.o) $(CLI_XSRC:%.cpp=$(BUILD)/%.o)
TEST_SRC  := $(sort $(wildcard tests/test_*.c))
TEST_BIN  := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
TESTLIB_SRC := $(filter-out $(TEST_SRC),$(sort $(wildcard tests/*.c)))
TESTLIB_OBJ := $(TESTLIB_SRC:%.c=$(BUILD)/%.o)
FUZZ_TARGETS := $(notdir $(patsubst %/,%,$(sort $(dir $(wildcard fuzz/*/fuzz.c)))))
FUZZ_REPLAY  := $(FUZZ_TARGETS:%=$(BUILD)/fuzz/%-replay)
BENCH_SRC := $(sort $(wildcard tests/bench/*.c))
BENCH_BIN := $(BENCH_SRC:tests/bench/%.c=$(BUILD)/bench/%)

STATIC_LIB := $(BUILD)/libroadsplat.a
SONAME     := libroadsplat.so.$(VERSION_MAJOR)
SHARED_LIB := $(BUILD)/libroadsplat.so.$(VERSION)
CLI        := $(BUILD)/roadsplat
PCFILE     := $(BUILD)/roadsplat.pc

DEPS_PKGS := libopenimageio-dev pkg-config clang libosmesa6-dev gnuplot-nox libclang-rt-14-dev locales python3-cairo

.PHONY: all lib cli test demo deps bench fuzz fuzz-smoke sanitize-test install uninstall help clean check-deps
.DEFAULT_GOAL := all
# keep objects of pattern rules (tests, fuzz replays) between runs
.SECONDARY:

all: lib cli

lib: $(STATIC_LIB) $(SHARED_LIB) $(BUILD)/libroadsplat.so $(PCFILE)

cli: check-deps $(CLI)

help:
	@echo "roadsplat $(VERSION) - targets:"
	@echo "  make demo          build and render docs/examples/ to out.png"
	@echo "  make test          build and run every test (unit, CLI, fuzz-corpus replay)"
	@echo "  make deps          install missing Debian packages (apt-get, needs root)"
	@echo "  make all           library (static + shared), roadsplat.pc and the CLI"
	@echo "  make bench         run the benchmarks, write docs/BENCHMARKS.md"
	@echo "  make fuzz          build libFuzzer targets with clang + ASan/UBSan"
	@echo "  make sanitize-test run the test suite under ASan + UBSan"
	@echo "  make fuzz-smoke    build and run every fuzz target FUZZ_SECONDS (30) each; fails on a finding"
	@echo "  make install       install to DESTDIR/PREFIX (PREFIX=$(PREFIX))"
	@echo "  make uninstall     remove what install put there"
	@echo "  make clean         remove $(BUILD)/"
	@echo "Variables: CC CXX OPT CFLAGS PREFIX DESTDIR BUILD WITH_OSMESA=0|1 FUZZ_SECONDS"

# --- dependencies -----------------------------------------------------------
# Installs only what is missing; without root, stops with the exact command.
deps:
	@missing=""; for p in $(DEPS_PKGS); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -z "$$missing" ]; then echo "deps: all present"; exit 0; fi; \
	if [ "$$(id -u)" != 0 ]; then \
	  echo "deps: missing:$$missing"; \
	  echo "deps: run as root: apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y$$missing"; exit 1; fi; \
	echo "deps: installing$$missing"; \
	export DEBIAN_FRONTEND=noninteractive; \
	apt-get update -q >/dev/null && apt-get install -y -q --no-install-recommends $$missing >/dev/null \
	  || { echo "deps: apt-get failed; run: apt-get update && apt-get install -y$$missing"; exit 1; }

check-deps:
	@$(PKG_CONFIG) --exists OpenImageIO 2>/dev/null || { \
	  echo "roadsplat CLI needs OpenImageIO: run 'make deps' (or: apt-get install -y libopenimageio-dev pkg-config)"; exit 1; }

# --- library ----------------------------------------------------------------
$(BUILD)/lib/%.o: lib/%.c include/roadsplat.h $(wildcard lib/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -c $< -o $@

$(STATIC_LIB): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	$(AR) rcs $@ $^

$(SHARED_LIB): $(LIB_OBJ)
	$(CC) -shared -Wl,-soname,$(SONAME) $(SAN) -o $@ $^ $(LDLIBS_CORE)

$(BUILD)/libroadsplat.so: $(SHARED_LIB)
	ln -sf libroadsplat.so.$(VERSION) $(BUILD)/$(SONAME)
	ln -sf libroadsplat.so.$(VERSION) $@

$(PCFILE): Makefile
	@mkdir -p $(dir $@)
	@printf 'prefix=%s\nlibdir=%s\nincludedir=%s\n\nName: roadsplat\nDescription: Burn roads into terrain textures; ROAM terrain meshing\nVersion: %s\nLibs: -L$${libdir} -lroadsplat\nLibs.private: -lm\nCflags: -I$${includedir}\n' \
	  '$(PREFIX)' '$(LIBDIR)' '$(INCDIR)' '$(VERSION)' > $@

# --- CLI (C + a small C++ shim around OpenImageIO) -----------------------------
$(BUILD)/cli/%.o: cli/%.c include/roadsplat.h $(wildcard cli/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L $(OSMESA_CFLAGS) -c $< -o $@

$(BUILD)/cli/%.o: cli/%.cpp $(wildcard cli/*.h)
	@mkdir -p $(dir $@)
	$(CXX) -std=c++17 $(OPT) $(SAN) -Wall -Wextra -Iinclude $(OIIO_CFLAGS) -c $< -o $@

$(CLI): $(CLI_OBJ) $(STATIC_LIB)
	$(CXX) $(SAN) -o $@ $(CLI_OBJ) $(STATIC_LIB) $(OIIO_LIBS) $(OSMESA_LIBS) $(LDLIBS_CORE) -lpthread

# --- tests --------------------------------------------------------------------
$(BUILD)/tests/%.o: tests/%.c include/roadsplat.h $(wildcard tests/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -Ilib -c $< -o $@

$(BUILD)/tests/test_%: $(BUILD)/tests/test_%.o $(TESTLIB_OBJ) $(STATIC_LIB)
	$(CC) $(SAN) -o $@ $^ $(LDLIBS_CORE) -lpthread

$(BUILD)/fuzz/%.o: fuzz/%.c include/roadsplat.h
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -c $< -o $@

$(BUILD)/fuzz/%-replay: $(BUILD)/fuzz/%/fuzz.o $(BUILD)/fuzz/replay_main.o $(STATIC_LIB)
	$(CC) $(SAN) -o $@ $^ $(LDLIBS_CORE)

# The demimage target drives the CLI's DEM loader: it also needs the CLI
# objects that hold it and OpenImageIO, linked as C++.
FUZZ_CLI_OBJ := $(BUILD)/cli/util.o $(BUILD)/cli/imageio.o
$(BUILD)/fuzz/demimage-replay: $(BUILD)/fuzz/demimage/fuzz.o $(BUILD)/fuzz/replay_main.o $(FUZZ_CLI_OBJ) $(STATIC_LIB)
	$(CXX) $(SAN) -o $@ $^ $(OIIO_LIBS) $(LDLIBS_CORE)

test: deps
	@$(MAKE) --no-print-directory all $(TEST_BIN) $(FUZZ_REPLAY)
	@BUILD=$(BUILD) SAN="$(SAN)" sh tests/run.sh

# --- demo ---------------------------------------------------------------------
demo: deps
	@$(MAKE) --no-print-directory all
	$(CLI) --cell-size 5 --z-scale 0.01 --stats $(BUILD)/demo-stats.json docs/examples/dem.pgm docs/examples/roads.txt out.png
	@echo "demo: wrote out.png (stats in $(BUILD)/demo-stats.json)"

# --- benchmarks ---------------------------------------------------------------
$(BUILD)/bench/%: tests/bench/%.c $(TESTLIB_OBJ) $(STATIC_LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -Ilib -Itests -o $@ $^ $(LDLIBS_CORE) -lpthread

bench: deps
	@$(MAKE) --no-print-directory all $(BENCH_BIN)
	@BUILD=$(BUILD) sh tests/bench/run.sh

# --- fuzzing and sanitizers -------------------------------------------------------
# `make fuzz` builds $(BUILD)/fuzz-bin/<target> for every fuzz/<target>/fuzz.c;
# fuzz/run.sh runs one (dictionary, working corpus in $(BUILD)/fuzz-corpus,
# log); `make fuzz-smoke` runs each for FUZZ_SECONDS and fails on a finding.
FUZZ_CC     ?= clang
FUZZ_CXX    ?= clang++
FUZZ_FLAGS  := -g -O1 -fsanitize=fuzzer,address,undefined,float-cast-overflow,float-divide-by-zero -fno-sanitize-recover=all
# Compare tracing costs 3-4x the executions. roam and splat take numbers
# modulo ranges (no magic values or keywords to find); demimage's parsers are
# OpenImageIO's (not instrumented) and lib/pgm.c, which the pgm target fuzzes
# with compare tracing. These three skip it; pgm and roads keep it.
FUZZ_NOCMP  := roam splat demimage
NOCMP_FLAG  := -fno-sanitize-coverage=trace-cmp
fuzz_cmp     = $(if $(filter $(1),$(FUZZ_NOCMP)),$(NOCMP_FLAG))
FUZZ_SECONDS ?= 30
FUZZ_OBJ    := $(BUILD)/fuzz-obj
fuzz:
	@mkdir -p $(BUILD)/fuzz-bin $(FUZZ_OBJ)
	@for t in $(filter-out demimage,$(FUZZ_TARGETS)); do \
	  echo "fuzz: $$t"; \
	  case " $(FUZZ_NOCMP) " in *" $$t "*) nocmp="$(NOCMP_FLAG)" ;; *) nocmp= ;; esac; \
	  $(FUZZ_CC) -std=c99 $(FUZZ_FLAGS) $$nocmp -Iinclude fuzz/$$t/fuzz.c $(LIB_SRC) -lm -o $(BUILD)/fuzz-bin/$$t || exit 1; \
	done
	@echo "fuzz: demimage (CLI DEM loader + OpenImageIO)"; \
	for f in $(LIB_SRC) cli/util.c fuzz/demimage/fuzz.c; do \
	  o=$(FUZZ_OBJ)/$$(echo $$f | tr / _).o; \
	  $(FUZZ_CC) -std=c99 $(FUZZ_FLAGS) $(call fuzz_cmp,demimage) -D_POSIX_C_SOURCE=200809L -Iinclude -c $$f -o $$o || exit 1; \
	done; \
	$(FUZZ_CXX) -std=c++17 $(FUZZ_FLAGS) $(call fuzz_cmp,demimage) -Iinclude $(OIIO_CFLAGS) -c cli/imageio.cpp -o $(FUZZ_OBJ)/cli_imageio.cpp.o || exit 1; \
	$(FUZZ_CXX) $(FUZZ_FLAGS) -o $(BUILD)/fuzz-bin/demimage $(FUZZ_OBJ)/*.o $(OIIO_LIBS) -lm || exit 1
	@echo "fuzz: binaries in $(BUILD)/fuzz-bin/ (run e.g. fuzz/run.sh pgm 60, with BUILD=$(BUILD))"

fuzz-smoke: fuzz
	@fail=0; for t in $(FUZZ_TARGETS); do \
	  BUILD=$(BUILD) FUZZ_LOG=$(BUILD)/fuzz-runs/smoke-$$t.log sh fuzz/run.sh $$t $(FUZZ_SECONDS) || fail=1; \
	done; [ $$fail = 0 ] || { echo "fuzz-smoke: FINDINGS (see $(BUILD)/fuzz-artifacts/)"; exit 1; }

sanitize-test:
	@LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 $(MAKE) --no-print-directory test BUILD=build/asan OPT="-O1 -g" \
	  SAN="-fsanitize=address,undefined,float-cast-overflow,float-divide-by-zero -fno-sanitize-recover=all -fno-omit-frame-pointer"

# --- install --------------------------------------------------------------------
install: all
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCDIR) $(DESTDIR)$(PKGCONFIGDIR) $(DESTDIR)$(MANDIR)/man1
	install -m 644 include/roadsplat.h $(DESTDIR)$(INCDIR)/roadsplat.h
	install -m 644 $(STATIC_LIB) $(DESTDIR)$(LIBDIR)/libroadsplat.a
	install -m 755 $(SHARED_LIB) $(DESTDIR)$(LIBDIR)/libroadsplat.so.$(VERSION)
	ln -sf libroadsplat.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(SONAME)
	ln -sf libroadsplat.so.$(VERSION) $(DESTDIR)$(LIBDIR)/libroadsplat.so
	install -m 644 $(PCFILE) $(DESTDIR)$(PKGCONFIGDIR)/roadsplat.pc
	install -m 755 $(CLI) $(DESTDIR)$(BINDIR)/roadsplat
	install -m 644 docs/roadsplat.1 $(DESTDIR)$(MANDIR)/man1/roadsplat.1

uninstall:
	rm -f $(DESTDIR)$(INCDIR)/roadsplat.h $(DESTDIR)$(LIBDIR)/libroadsplat.a \
	  $(DESTDIR)$(LIBDIR)/libroadsplat.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(SONAME) \
	  $(DESTDIR)$(LIBDIR)/libroadsplat.so $(DESTDIR)$(PKGCONFIGDIR)/roadsplat.pc \
	  $(DESTDIR)$(BINDIR)/roadsplat $(DESTDIR)$(MANDIR)/man1/roadsplat.1

clean:
	rm -rf $(BUILD)
