# roadsplat - see `make help`.
#
# Build outputs go to $(BUILD) (default build/). Sanitizer builds use their own
# folders (build/asan), so they never mix objects with the normal build.

# One version source: the RS_VERSION_* macros of include/roadsplat.h.
rs_version    = $(shell sed -n 's/^\#define RS_VERSION_$(1) *\([0-9][0-9]*\).*/\1/p' include/roadsplat.h)
VERSION_MAJOR := $(call rs_version,MAJOR)
VERSION_MINOR := $(call rs_version,MINOR)
VERSION_PATCH := $(call rs_version,PATCH)
VERSION       := $(VERSION_MAJOR).$(VERSION_MINOR).$(VERSION_PATCH)

PREFIX  ?= /usr/local
DESTDIR ?=
BINDIR  ?= $(PREFIX)/bin
LIBDIR  ?= $(PREFIX)/lib
INCDIR  ?= $(PREFIX)/include
MANDIR  ?= $(PREFIX)/share/man
PKGCONFIGDIR ?= $(LIBDIR)/pkgconfig
# Optional CLI modules (roadsplat-image.so, roadsplat-render.so); the CLI
# looks next to itself first, then here (cli/module.c).
MODULEDIR ?= $(LIBDIR)/roadsplat

BUILD   ?= build
# The sub-makes of test, demo, bench and fuzz build with one job per core
# unless the caller gave -j (then its jobserver is used).
JOBS      ?= $(shell nproc 2>/dev/null || echo 1)
JOBS_FLAG = $(if $(filter -j%,$(MAKEFLAGS)),,-j$(JOBS))
CC      ?= cc
CXX     ?= c++
OPT     ?= -O2 -g
# No -ffast-math anywhere: it removes the NaN checks the library relies on.
WARN    := -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wvla
# CPPFLAGS, CFLAGS, CXXFLAGS and LDFLAGS from the environment or the command
# line come last, so they can override ours.
CFLAGS  ?=
CXXFLAGS ?=
CPPFLAGS ?=
LDFLAGS ?=
SAN     ?=
DEPFLAGS := -MMD -MP
# lib/ (docs/design.md "Layout"): input/ parsers and the atlas, scene/ the
# prepared roads (network, road field, styles, line symbols, markings),
# splat/ the splatter and its stages, roam/ the mesher, gpu/ the GPU export;
# the context, options and DEM at the top. Private headers by bare name.
LIB_DIRS  := lib lib/input lib/scene lib/splat lib/roam lib/gpu
LIB_INC   := $(addprefix -I,$(LIB_DIRS))
ALL_CFLAGS := -std=c99 $(OPT) $(WARN) $(SAN) -Iinclude $(LIB_INC) -fvisibility=hidden -fPIC $(DEPFLAGS) $(CPPFLAGS) $(CFLAGS)
ALL_CXXFLAGS := -std=c++17 $(OPT) $(SAN) -Wall -Wextra -Iinclude -fPIC $(DEPFLAGS) $(CPPFLAGS) $(CXXFLAGS)
LDLIBS_CORE := -lm

PKG_CONFIG ?= pkg-config
OIIO_CFLAGS = $(shell $(PKG_CONFIG) --cflags OpenImageIO 2>/dev/null)
OIIO_LIBS   = $(shell $(PKG_CONFIG) --libs OpenImageIO 2>/dev/null)
# PNG output (cli/png.c): libdeflate compresses, zlib joins the bands'
# streams (inflate's Z_BLOCK when a piece has several blocks, adler32_combine).
DEFLATE_CFLAGS = $(shell $(PKG_CONFIG) --cflags libdeflate zlib 2>/dev/null)
DEFLATE_LIBS   = $(or $(shell $(PKG_CONFIG) --libs libdeflate 2>/dev/null),-ldeflate) \
                 $(or $(shell $(PKG_CONFIG) --libs zlib 2>/dev/null),-lz)
# SHA-256 of the tiles and the manifest (cli/sha256.c): Nettle.
NETTLE_LIBS    = $(or $(shell $(PKG_CONFIG) --libs nettle 2>/dev/null),-lnettle)
# The default PNG level 1 by ISA-L's igzip (libisal-dev; its level 0, whose
# bytes are the same in every process: docs/packaging.md "Deterministic bytes"),
# 2.5x faster than libdeflate's level 1 here: auto-detected, or forced with
# WITH_ISAL=1/0.
WITH_ISAL ?= $(shell [ -f /usr/include/isa-l/igzip_lib.h ] && echo 1 || echo 0)
ifeq ($(WITH_ISAL),1)
DEFLATE_CFLAGS += -DRS_WITH_ISAL
DEFLATE_LIBS   += $(or $(shell $(PKG_CONFIG) --libs libisal 2>/dev/null),-lisal)
endif

# Optional OSMesa renderer: auto-detected, or forced with WITH_OSMESA=1/0.
WITH_OSMESA ?= $(shell $(PKG_CONFIG) --exists osmesa 2>/dev/null && echo 1 || echo 0)
ifeq ($(WITH_OSMESA),1)
OSMESA_CFLAGS = -DRS_WITH_OSMESA $(shell $(PKG_CONFIG) --cflags osmesa 2>/dev/null)
OSMESA_LIBS   = $(or $(shell $(PKG_CONFIG) --libs osmesa 2>/dev/null),-lOSMesa)
endif

# Optional GDAL layer (georeferenced DEMs, OGR roads, GeoTIFF output; issue
# 17): auto-detected, or forced with WITH_GDAL=1/0. Its headers are system
# headers here (-isystem), so the project's warnings do not apply to them.
WITH_GDAL ?= $(shell $(PKG_CONFIG) --exists gdal 2>/dev/null && echo 1 || echo 0)
ifeq ($(WITH_GDAL),1)
GDAL_CFLAGS = $(patsubst -I%,-isystem %,$(shell $(PKG_CONFIG) --cflags gdal 2>/dev/null))
GDAL_LIBS   = $(or $(shell $(PKG_CONFIG) --libs gdal 2>/dev/null),-lgdal)
GDAL_DEF    = -DRS_WITH_GDAL
endif

# Optional MBTiles output of `roadsplat tiles` (SQLite, in the module
# roadsplat-mbtiles.so): auto-detected, or forced with WITH_SQLITE=1/0.
WITH_SQLITE ?= $(shell $(PKG_CONFIG) --exists sqlite3 2>/dev/null && echo 1 || echo 0)
ifeq ($(WITH_SQLITE),1)
SQLITE_DEF  = -DRS_WITH_SQLITE
SQLITE_LIBS = $(or $(shell $(PKG_CONFIG) --libs sqlite3 2>/dev/null),-lsqlite3)
endif

# Optional glTF output of `roadsplat mesh` (module roadsplat-gltf.so, cli/gltf.c:
# vertex cache and fetch order by meshoptimizer, which has no .pc file):
# auto-detected by its header, or forced with WITH_MESHOPT=1/0.
WITH_MESHOPT ?= $(shell [ -f /usr/include/meshoptimizer.h ] && echo 1 || echo 0)
ifeq ($(WITH_MESHOPT),1)
MESHOPT_DEF  = -DRS_WITH_MESHOPT
MESHOPT_LIBS = -lmeshoptimizer
endif

# Optional OpenDRIVE reader (module roadsplat-odr.so, cli/odr.c): expat, a
# small streaming XML parser (docs/opendrive.md says why not libxml2);
# auto-detected, or forced with WITH_EXPAT=1/0.
WITH_EXPAT ?= $(shell $(PKG_CONFIG) --exists expat 2>/dev/null && echo 1 || echo 0)
ifeq ($(WITH_EXPAT),1)
EXPAT_DEF  = -DRS_WITH_EXPAT
EXPAT_LIBS = $(or $(shell $(PKG_CONFIG) --libs expat 2>/dev/null),-lexpat)
endif

LIB_SRC   := $(sort $(wildcard $(addsuffix /*.c,$(LIB_DIRS))))
LIB_OBJ   := $(LIB_SRC:%.c=$(BUILD)/%.o)
# The executable links only libc, libm, libdl, libdeflate, zlib, ISA-L and Nettle; OpenImageIO
# (cli/imageio.cpp) and OSMesa (cli/render*.c) live in modules it dlopens on
# first use (docs/packaging.md).
RENDER_SRC := cli/render.c cli/render_gl.c cli/render_shader.c cli/render_vt.c
GDAL_SRC  := cli/gdal.c cli/mercator_gdal.c
MBTILES_SRC := cli/mbtiles.c
GLTF_SRC  := cli/gltf.c
ODR_SRC   := cli/odr.c
CLI_CSRC  := $(filter-out $(RENDER_SRC) $(GDAL_SRC) $(MBTILES_SRC) $(GLTF_SRC) $(ODR_SRC),$(sort $(wildcard cli/*.c)))
CLI_OBJ   := $(CLI_CSRC:%.c=$(BUILD)/%.o)
RENDER_OBJ := $(RENDER_SRC:%.c=$(BUILD)/%.o)
IMAGE_OBJ := $(BUILD)/cli/imageio.o
IMAGE_MOD := $(BUILD)/roadsplat-image.so
RENDER_MOD := $(BUILD)/roadsplat-render.so
GDAL_MOD  := $(BUILD)/roadsplat-gdal.so
MBTILES_MOD := $(BUILD)/roadsplat-mbtiles.so
GLTF_MOD  := $(BUILD)/roadsplat-gltf.so
ODR_MOD   := $(BUILD)/roadsplat-odr.so
MODULES   := $(IMAGE_MOD) $(if $(filter 1,$(WITH_OSMESA)),$(RENDER_MOD)) $(if $(filter 1,$(WITH_GDAL)),$(GDAL_MOD)) \
             $(if $(filter 1,$(WITH_SQLITE)),$(MBTILES_MOD)) $(if $(filter 1,$(WITH_MESHOPT)),$(GLTF_MOD)) \
             $(if $(filter 1,$(WITH_EXPAT)),$(ODR_MOD))
TEST_SRC  := $(sort $(wildcard tests/test_*.c))
TEST_BIN  := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
TESTLIB_SRC := $(filter-out $(TEST_SRC),$(sort $(wildcard tests/*.c)))
TESTLIB_OBJ := $(TESTLIB_SRC:%.c=$(BUILD)/%.o)
FUZZ_TARGETS := $(notdir $(patsubst %/,%,$(sort $(dir $(wildcard fuzz/*/fuzz.c)))))
ifneq ($(WITH_EXPAT),1)
FUZZ_TARGETS := $(filter-out odr,$(FUZZ_TARGETS))
endif
FUZZ_REPLAY  := $(FUZZ_TARGETS:%=$(BUILD)/fuzz/%-replay)
BENCH_SRC := $(sort $(wildcard tests/bench/*.c))
BENCH_BIN := $(BENCH_SRC:tests/bench/%.c=$(BUILD)/bench/%)

STATIC_LIB := $(BUILD)/libroadsplat.a
SONAME     := libroadsplat.so.$(VERSION_MAJOR)
SHARED_LIB := $(BUILD)/libroadsplat.so.$(VERSION)
CLI        := $(BUILD)/roadsplat
PCFILE     := $(BUILD)/roadsplat.pc

DEPS_PKGS := libopenimageio-dev libdeflate-dev zlib1g-dev libisal-dev nettle-dev pkg-config clang libosmesa6-dev gnuplot-nox libclang-rt-14-dev locales python3-cairo libgdal-dev gdal-bin libsqlite3-dev parallel time bc libmeshoptimizer-dev libjs-leaflet libexpat1-dev

# Settings baked into generated files ($(PCFILE), the module folder in
# cli/module.o): $(CONFIG) is rewritten whenever they change, e.g. by
# `make install PREFIX=/opt/x` after `make`, so those files follow.
CONFIG      := $(BUILD)/config.txt
CONFIG_TEXT := prefix=$(PREFIX) libdir=$(LIBDIR) includedir=$(INCDIR) moduledir=$(MODULEDIR) version=$(VERSION)

.PHONY: strip atlas all lib cli test demo deps deps-viewer bench fuzz fuzz-smoke sanitize-test install install-lib uninstall help clean check-deps FORCE
.DEFAULT_GOAL := all
# keep objects of pattern rules (tests, fuzz replays) between runs
.SECONDARY:

all: lib cli

lib: $(STATIC_LIB) $(SHARED_LIB) $(BUILD)/libroadsplat.so $(PCFILE)

cli: check-deps $(CLI) $(MODULES)

help:
	@echo "roadsplat $(VERSION) - targets:"
	@echo "  make demo          build and render docs/examples/ to out.png"
	@echo "  make test          build and run every test (unit, CLI, fuzz-corpus replay)"
	@echo "  make deps          install missing Debian packages (apt-get, needs root)"
	@echo "  make deps-viewer   install Debian's chromium for the tile viewer's screenshot test (optional)"
	@echo "  make all           library (static + shared), roadsplat.pc and the CLI"
	@echo "  make bench         run the benchmarks, write docs/BENCHMARKS.md"
	@echo "  make fuzz          build libFuzzer targets with clang + ASan/UBSan"
	@echo "  make sanitize-test run the test suite under ASan + UBSan"
	@echo "  make fuzz-smoke    build and run every fuzz target FUZZ_SECONDS (30) each; fails on a finding"
	@echo "  make install       install to DESTDIR/PREFIX (PREFIX=$(PREFIX))"
	@echo "  make install-lib   install only the library, header and roadsplat.pc (no OpenImageIO needed)"
	@echo "  make uninstall     remove what install put there"
	@echo "  make clean         remove $(BUILD)/"
	@echo "Variables: CC CXX OPT CPPFLAGS CFLAGS CXXFLAGS LDFLAGS PREFIX DESTDIR LIBDIR BUILD WITH_OSMESA=0|1 WITH_GDAL=0|1 WITH_SQLITE=0|1 WITH_MESHOPT=0|1 WITH_EXPAT=0|1 FUZZ_SECONDS JOBS (build and fuzz-smoke jobs; default: cores) TEST_JOBS (tests/run.sh)"

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

# Debian's chromium (about 300 MB) only for the screenshot checks of
# tests/cli_viewer_test.sh, which say SKIP without it: not part of `make deps`.
deps-viewer:
	@command -v chromium >/dev/null 2>&1 && { echo "deps-viewer: chromium present"; exit 0; }; \
	if [ "$$(id -u)" != 0 ]; then echo "deps-viewer: run as root: apt-get update && apt-get install -y chromium"; exit 1; fi; \
	export DEBIAN_FRONTEND=noninteractive; \
	apt-get update -q >/dev/null && apt-get install -y -q --no-install-recommends chromium >/dev/null \
	  || { echo "deps-viewer: apt-get failed; run: apt-get update && apt-get install -y chromium"; exit 1; }

check-deps:
	@$(PKG_CONFIG) --exists OpenImageIO 2>/dev/null || { \
	  echo "roadsplat CLI needs OpenImageIO: run 'make deps' (or: apt-get install -y libopenimageio-dev pkg-config)"; exit 1; }
	@$(PKG_CONFIG) --exists libdeflate 2>/dev/null || [ -f /usr/include/libdeflate.h ] || { \
	  echo "roadsplat CLI needs libdeflate: run 'make deps' (or: apt-get install -y libdeflate-dev)"; exit 1; }
	@$(PKG_CONFIG) --exists zlib 2>/dev/null || [ -f /usr/include/zlib.h ] || { \
	  echo "roadsplat CLI needs zlib: run 'make deps' (or: apt-get install -y zlib1g-dev)"; exit 1; }
	@$(PKG_CONFIG) --exists nettle 2>/dev/null || [ -f /usr/include/nettle/sha2.h ] || { \
	  echo "roadsplat CLI needs Nettle: run 'make deps' (or: apt-get install -y nettle-dev)"; exit 1; }

$(CONFIG): FORCE
	@mkdir -p $(dir $@)
	@[ "$$(cat $@ 2>/dev/null)" = '$(CONFIG_TEXT)' ] || echo '$(CONFIG_TEXT)' > $@

# --- library ----------------------------------------------------------------
$(BUILD)/lib/%.o: lib/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -c $< -o $@

$(STATIC_LIB): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	$(AR) rcs $@ $^

$(SHARED_LIB): $(LIB_OBJ)
	$(CC) -shared -Wl,-soname,$(SONAME) $(SAN) $(LDFLAGS) -o $@ $^ $(LDLIBS_CORE)

$(BUILD)/libroadsplat.so: $(SHARED_LIB)
	ln -sf libroadsplat.so.$(VERSION) $(BUILD)/$(SONAME)
	ln -sf libroadsplat.so.$(VERSION) $@

$(PCFILE): $(CONFIG)
	@mkdir -p $(dir $@)
	@printf 'prefix=%s\nlibdir=%s\nincludedir=%s\n\nName: roadsplat\nDescription: Burn roads into terrain textures; ROAM terrain meshing\nVersion: %s\nLibs: -L$${libdir} -lroadsplat\nLibs.private: -lm\nCflags: -I$${includedir}\n' \
	  '$(PREFIX)' '$(LIBDIR)' '$(INCDIR)' '$(VERSION)' > $@

# --- CLI: C executable + modules (C++ shim around OpenImageIO; OSMesa) --------
# CLI symbols keep default visibility: the executable exports them
# (--export-dynamic) to the modules, which call back into it. The whole
# library is linked in, since the render module uses parts the rest does not.
CLI_CFLAGS = $(ALL_CFLAGS) -fvisibility=default -D_POSIX_C_SOURCE=200809L $(OSMESA_CFLAGS) $(DEFLATE_CFLAGS) $(GDAL_DEF) $(SQLITE_DEF) $(MESHOPT_DEF) $(EXPAT_DEF)
$(BUILD)/cli/%.o: cli/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CLI_CFLAGS) -c $< -o $@

$(BUILD)/cli/module.o: cli/module.c $(CONFIG)
	@mkdir -p $(dir $@)
	$(CC) $(CLI_CFLAGS) -DRS_MODULEDIR='"$(MODULEDIR)"' -c $< -o $@

$(BUILD)/cli/gdal.o $(BUILD)/cli/mercator_gdal.o: $(BUILD)/cli/%.o: cli/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CLI_CFLAGS) $(GDAL_CFLAGS) -c $< -o $@

$(BUILD)/cli/%.o: cli/%.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(ALL_CXXFLAGS) $(OIIO_CFLAGS) -c $< -o $@

$(CLI): $(CLI_OBJ) $(STATIC_LIB)
	$(CC) $(SAN) $(LDFLAGS) -Wl,--export-dynamic -o $@ $(CLI_OBJ) -Wl,--whole-archive $(STATIC_LIB) -Wl,--no-whole-archive \
	  $(DEFLATE_LIBS) $(NETTLE_LIBS) -ldl $(LDLIBS_CORE) -lpthread

$(IMAGE_MOD): $(IMAGE_OBJ)
	$(CXX) -shared $(SAN) $(LDFLAGS) -o $@ $^ $(OIIO_LIBS)

$(RENDER_MOD): $(RENDER_OBJ)
	$(CC) -shared $(SAN) $(LDFLAGS) -o $@ $^ $(OSMESA_LIBS) $(LDLIBS_CORE)

$(GDAL_MOD): $(BUILD)/cli/gdal.o $(BUILD)/cli/mercator_gdal.o
	$(CC) -shared $(SAN) $(LDFLAGS) -o $@ $^ $(GDAL_LIBS) $(LDLIBS_CORE)

$(MBTILES_MOD): $(BUILD)/cli/mbtiles.o
	$(CC) -shared $(SAN) $(LDFLAGS) -o $@ $^ $(SQLITE_LIBS)

$(GLTF_MOD): $(BUILD)/cli/gltf.o
	$(CC) -shared $(SAN) $(LDFLAGS) -o $@ $^ $(MESHOPT_LIBS) $(LDLIBS_CORE)

# The OpenDRIVE module carries the library parts it uses (lib/input/odr_*.c and
# what they call), kept local to it (--exclude-libs).
$(ODR_MOD): $(BUILD)/cli/odr.o $(STATIC_LIB)
	$(CC) -shared $(SAN) $(LDFLAGS) -Wl,--exclude-libs,ALL -o $@ $(BUILD)/cli/odr.o $(STATIC_LIB) $(EXPAT_LIBS) $(LDLIBS_CORE)

# --- tests --------------------------------------------------------------------
$(BUILD)/tests/%.o: tests/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -Ilib -c $< -o $@

$(BUILD)/tests/test_%: $(BUILD)/tests/test_%.o $(TESTLIB_OBJ) $(STATIC_LIB)
	$(CC) $(SAN) $(LDFLAGS) -o $@ $^ $(LDLIBS_CORE) -lpthread

$(BUILD)/fuzz/%.o: fuzz/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -c $< -o $@

$(BUILD)/fuzz/%-replay: $(BUILD)/fuzz/%/fuzz.o $(BUILD)/fuzz/replay_main.o $(STATIC_LIB)
	$(CC) $(SAN) $(LDFLAGS) -o $@ $^ $(LDLIBS_CORE)

# The odr target reads OpenDRIVE XML with the module's reader (cli/odr.c) and expat.
$(BUILD)/fuzz/odr-replay: $(BUILD)/fuzz/odr/fuzz.o $(BUILD)/fuzz/replay_main.o $(BUILD)/cli/odr.o $(STATIC_LIB)
	$(CC) $(SAN) $(LDFLAGS) -o $@ $^ $(EXPAT_LIBS) $(LDLIBS_CORE)

# The demimage target drives the CLI's DEM loader: it also needs the CLI
# objects that hold it and OpenImageIO, linked as C++.
FUZZ_CLI_OBJ := $(BUILD)/cli/util.o $(BUILD)/cli/bigalloc.o $(BUILD)/cli/imageio.o
$(BUILD)/fuzz/demimage-replay: $(BUILD)/fuzz/demimage/fuzz.o $(BUILD)/fuzz/replay_main.o $(FUZZ_CLI_OBJ) $(STATIC_LIB)
	$(CXX) $(SAN) $(LDFLAGS) -o $@ $^ $(OIIO_LIBS) $(LDLIBS_CORE)

# PNG writer test (C++: reads back through OpenImageIO, and libpng directly).
# It doubles as the benchmark's OpenImageIO/libpng writer (tests/bench/write.sh).
TEST_PNG_OBJ := $(BUILD)/cli/png.o $(BUILD)/cli/util.o $(BUILD)/cli/bigalloc.o $(BUILD)/cli/imageio.o
$(BUILD)/tests/test_png: tests/png/test_png.cpp $(TEST_PNG_OBJ) $(STATIC_LIB)
	@mkdir -p $(dir $@)
	$(CXX) $(ALL_CXXFLAGS) $(OIIO_CFLAGS) $(DEFLATE_CFLAGS) -o $@ $< $(TEST_PNG_OBJ) $(LDFLAGS) $(STATIC_LIB) $(OIIO_LIBS) -lpng \
	  $(DEFLATE_LIBS) $(LDLIBS_CORE)

# The PNG writer's bytes in one process (tests/cli_odr_test.sh runs it in many).
$(BUILD)/tools/png_repeat: tests/tools/png_repeat.c $(BUILD)/cli/png.o
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -Icli $(LDFLAGS) -o $@ $^ $(DEFLATE_LIBS) $(LDLIBS_CORE) -lpthread

# cli/numfmt.c against printf (tests/cli_mesh_test.sh runs it).
$(BUILD)/tools/numfmt_check: tests/tools/numfmt_check.c $(BUILD)/cli/numfmt.o
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -Icli $(LDFLAGS) -o $@ $^ $(LDLIBS_CORE)

# Helper programs of the tests and benchmarks (not run by themselves).
$(BUILD)/tools/%: tests/tools/%.c $(TESTLIB_OBJ) $(STATIC_LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -Ilib -Itests $(LDFLAGS) -o $@ $^ $(LDLIBS_CORE) -lpthread

# splat_dump twice: as the library is, and with lib/splat/surface.c and
# composite.c built without their AVX-512 paths
# (tests/cli_surface_paths_test.sh compares them).
$(BUILD)/tests/%_portable.o: lib/splat/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -DRS_NO_AVX512 -c $< -o $@

$(BUILD)/tools/splat_dump_portable: tests/tools/splat_dump.c $(TESTLIB_OBJ) \
  $(filter-out $(BUILD)/lib/splat/surface.o $(BUILD)/lib/splat/composite.o,$(LIB_OBJ)) \
  $(BUILD)/tests/surface_portable.o $(BUILD)/tests/composite_portable.o
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -Ilib -Itests $(LDFLAGS) -o $@ $^ $(LDLIBS_CORE) -lpthread

# (the benchmarks are built too, not run: one that no longer compiles fails here, not at `make bench`)
test: deps
	@$(MAKE) --no-print-directory $(JOBS_FLAG) all $(TEST_BIN) $(FUZZ_REPLAY) $(BUILD)/tests/test_png $(BUILD)/tools/png_repeat $(BUILD)/tools/numfmt_check $(BUILD)/atlasgen $(BUILD)/tools/grid_compare \
	  $(BUILD)/tools/splat_dump $(BUILD)/tools/splat_dump_portable $(BENCH_BIN)
	@BUILD=$(BUILD) SAN="$(SAN)" OPT="$(OPT)" sh tests/run.sh

# --- demo ---------------------------------------------------------------------
demo: deps
	@$(MAKE) --no-print-directory $(JOBS_FLAG) all
	$(CLI) --cell-size 5 --z-scale 0.01 --stats $(BUILD)/demo-stats.json docs/examples/dem.pgm docs/examples/roads.txt out.png
	$(CLI) --cell-size 2 --z-scale 0.01 --texels 20 docs/examples/junction-dem.pgm docs/examples/junction.txt junction.png
	@if [ -f $(ODR_MOD) ]; then \
	  echo "$(CLI) --cell-size 2 --origin 0,100 --texels 20 --z-scale 0.01 docs/examples/crossing-dem.pgm docs/examples/crossing.xodr crossing.png"; \
	  $(CLI) --cell-size 2 --origin 0,100 --texels 20 --z-scale 0.01 docs/examples/crossing-dem.pgm docs/examples/crossing.xodr crossing.png || exit 1; \
	  echo "demo: wrote crossing.png (OpenDRIVE, docs/opendrive.md)"; \
	else echo "demo: SKIP crossing.xodr: OpenDRIVE needs expat (make deps installs libexpat1-dev; then rebuild)"; fi
	@echo "demo: wrote out.png (stats in $(BUILD)/demo-stats.json) and junction.png (road markings at 0.1 m per pixel)"

# --- benchmarks ---------------------------------------------------------------
$(BUILD)/bench/%: tests/bench/%.c $(TESTLIB_OBJ) $(STATIC_LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -D_POSIX_C_SOURCE=200809L -Ilib -Itests $(LDFLAGS) -o $@ $^ $(LDLIBS_CORE) -lpthread

bench: deps
	@$(MAKE) --no-print-directory $(JOBS_FLAG) all $(BENCH_BIN) $(BUILD)/tests/test_png $(BUILD)/tools/demgen $(BUILD)/tools/citygen \
	  $(BUILD)/tools/numfmt_check
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
# OpenImageIO's (not instrumented) and lib/input/pgm.c, which the pgm target fuzzes
# with compare tracing. These three skip it; pgm and roads keep it.
FUZZ_NOCMP  := roam splat demimage options
NOCMP_FLAG  := -fno-sanitize-coverage=trace-cmp
FUZZ_SECONDS ?= 30
FUZZ_OBJ    := $(BUILD)/fuzz-obj
# The library is compiled once per instrumentation (cmp/, nocmp/) and every
# target links those objects, in parallel: compiling it for each of the 13
# targets in turn took 8 minutes of CI.
fuzz_var     = $(if $(filter $(1),$(FUZZ_NOCMP)),nocmp,cmp)
FUZZ_BIN    := $(FUZZ_TARGETS:%=$(BUILD)/fuzz-bin/%)
$(FUZZ_OBJ)/cmp/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) -std=c99 $(FUZZ_FLAGS) -D_POSIX_C_SOURCE=200809L -Iinclude $(LIB_INC) $(DEPFLAGS) -c $< -o $@
$(FUZZ_OBJ)/nocmp/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) -std=c99 $(FUZZ_FLAGS) $(NOCMP_FLAG) -D_POSIX_C_SOURCE=200809L -Iinclude $(LIB_INC) $(DEPFLAGS) -c $< -o $@
$(FUZZ_OBJ)/%/cli/imageio.o: cli/imageio.cpp
	@mkdir -p $(dir $@)
	$(FUZZ_CXX) -std=c++17 $(FUZZ_FLAGS) $(if $(filter nocmp,$*),$(NOCMP_FLAG)) -Iinclude $(OIIO_CFLAGS) $(DEPFLAGS) -c $< -o $@
# fuzz_rule(target, extra objects beneath the variant's folder, extra libraries, linker)
define fuzz_rule
$(BUILD)/fuzz-bin/$(1): $(FUZZ_OBJ)/$(call fuzz_var,$(1))/fuzz/$(1)/fuzz.o $(addprefix $(FUZZ_OBJ)/$(call fuzz_var,$(1))/,$(LIB_SRC:.c=.o) $(2))
	@mkdir -p $$(dir $$@)
	$(4) $(FUZZ_FLAGS) -o $$@ $$^ $(3) -lm
endef
$(foreach t,$(filter-out demimage odr,$(FUZZ_TARGETS)),$(eval $(call fuzz_rule,$(t),,,$(FUZZ_CC))))
$(eval $(call fuzz_rule,demimage,cli/util.o cli/bigalloc.o cli/imageio.o,$(OIIO_LIBS),$(FUZZ_CXX)))
$(eval $(call fuzz_rule,odr,cli/odr.o,$(EXPAT_LIBS),$(FUZZ_CC)))
fuzz:
	@$(MAKE) --no-print-directory $(JOBS_FLAG) $(FUZZ_BIN)
	@echo "fuzz: binaries in $(BUILD)/fuzz-bin/ (run e.g. fuzz/run.sh pgm 60, with BUILD=$(BUILD))"

# Targets the smoke leaves out (none: split's open findings were worked
# through on 2 December 2026, docs/ROBUSTNESS.md).
FUZZ_SMOKE_SKIP :=
# The targets run one per core (xargs -P; each is one process).
fuzz-smoke: fuzz
	@printf '%s\n' $(filter-out $(FUZZ_SMOKE_SKIP),$(FUZZ_TARGETS)) | \
	  xargs -P $(JOBS) -I{} env BUILD=$(BUILD) FUZZ_LOG=$(BUILD)/fuzz-runs/smoke-{}.log sh fuzz/run.sh {} $(FUZZ_SECONDS) \
	  || { echo "fuzz-smoke: FINDINGS (see $(BUILD)/fuzz-artifacts/)"; exit 1; }

sanitize-test:
	@LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 $(MAKE) --no-print-directory test BUILD=build/asan OPT="-O1 -g" \
	  SAN="-fsanitize=address,undefined,float-cast-overflow,float-divide-by-zero -fno-sanitize-recover=all -fno-omit-frame-pointer"

# --- install --------------------------------------------------------------------
# install-lib: library, header and roadsplat.pc only (needs neither
# OpenImageIO nor libdeflate); install: that plus the CLI, its modules and
# the man page. Both regenerate what names PREFIX first ($(CONFIG)).
install-lib: lib
	install -d $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCDIR) $(DESTDIR)$(PKGCONFIGDIR)
	install -m 644 include/roadsplat.h $(DESTDIR)$(INCDIR)/roadsplat.h
	install -m 644 include/roadsplat_experimental.h $(DESTDIR)$(INCDIR)/roadsplat_experimental.h
	install -m 644 $(STATIC_LIB) $(DESTDIR)$(LIBDIR)/libroadsplat.a
	install -m 755 $(SHARED_LIB) $(DESTDIR)$(LIBDIR)/libroadsplat.so.$(VERSION)
	ln -sf libroadsplat.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(SONAME)
	ln -sf libroadsplat.so.$(VERSION) $(DESTDIR)$(LIBDIR)/libroadsplat.so
	install -m 644 $(PCFILE) $(DESTDIR)$(PKGCONFIGDIR)/roadsplat.pc

install: install-lib cli
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(MODULEDIR) $(DESTDIR)$(MANDIR)/man1
	install -m 755 $(CLI) $(DESTDIR)$(BINDIR)/roadsplat
	install -m 755 $(MODULES) $(DESTDIR)$(MODULEDIR)/
	install -m 644 docs/roadsplat.1 $(DESTDIR)$(MANDIR)/man1/roadsplat.1

uninstall:
	rm -f $(DESTDIR)$(INCDIR)/roadsplat.h $(DESTDIR)$(INCDIR)/roadsplat_experimental.h $(DESTDIR)$(LIBDIR)/libroadsplat.a \
	  $(DESTDIR)$(LIBDIR)/libroadsplat.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(SONAME) \
	  $(DESTDIR)$(LIBDIR)/libroadsplat.so $(DESTDIR)$(PKGCONFIGDIR)/roadsplat.pc \
	  $(DESTDIR)$(BINDIR)/roadsplat $(DESTDIR)$(MANDIR)/man1/roadsplat.1 \
	  $(DESTDIR)$(MODULEDIR)/roadsplat-image.so $(DESTDIR)$(MODULEDIR)/roadsplat-render.so \
	  $(DESTDIR)$(MODULEDIR)/roadsplat-gdal.so $(DESTDIR)$(MODULEDIR)/roadsplat-mbtiles.so \
	  $(DESTDIR)$(MODULEDIR)/roadsplat-gltf.so $(DESTDIR)$(MODULEDIR)/roadsplat-odr.so
	-rmdir $(DESTDIR)$(MODULEDIR) 2>/dev/null

clean:
	rm -rf $(BUILD)

# Header dependencies written by the compiler (-MMD -MP).
-include $(wildcard $(BUILD)/lib/*.d $(BUILD)/lib/*/*.d $(BUILD)/cli/*.d $(BUILD)/tests/*.d $(BUILD)/tests/*/*.d $(BUILD)/fuzz/*.d $(BUILD)/fuzz/*/*.d \
  $(FUZZ_OBJ)/*/*/*.d $(FUZZ_OBJ)/*/*/*/*.d)

# --- the built-in marking atlas -----------------------------------------------
# lib/input/atlas_default.c is generated and committed; `make atlas` regenerates it
# (and $(BUILD)/markings/atlas.png + atlas-index.txt, the same atlas as the
# files `roadsplat --atlas IMG --atlas-index FILE` reads).
$(BUILD)/atlasgen: tests/tools/atlasgen.c
	@mkdir -p $(dir $@)
	$(CC) -std=c99 $(OPT) $(WARN) -D_POSIX_C_SOURCE=200809L -o $@ $< -lm

# The bundled road-surface strip (docs/surface.md): docs/examples/asphalt-strip.png
# is generated by tests/tools/stripgen.c and committed; `make strip` regenerates it.
$(BUILD)/tools/stripgen: tests/tools/stripgen.c
	@mkdir -p $(dir $@)
	$(CC) -std=c99 $(OPT) $(WARN) -D_POSIX_C_SOURCE=200809L $(DEFLATE_CFLAGS) -o $@ $< -lz -lm

strip: $(BUILD)/tools/stripgen
	$(BUILD)/tools/stripgen docs/examples/asphalt-strip.png

atlas: $(BUILD)/atlasgen
	@mkdir -p $(BUILD)/markings
	$(BUILD)/atlasgen lib/input/atlas_default.c $(BUILD)/markings/atlas.png $(BUILD)/markings/atlas-index.txt
