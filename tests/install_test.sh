#!/bin/sh
# Packaging test (tests/run.sh runs it): `make install PREFIX=<tmp>` after the
# normal build, then
# - roadsplat.pc names that prefix (it used to keep /usr/local);
# - a C and a C++ program build through pkg-config, against the shared library
#   (and the C one against the static library too) and print the version;
# - the installed CLI runs, and finds its modules in $(LIBDIR)/roadsplat (a PNG
#   DEM needs the image module); without the module it names the module;
# - make uninstall removes everything it installed; then `make all` puts the
#   build folder back to its own prefix.
# Usage: sh tests/install_test.sh BUILD   (SAN and OPT as for the build)
B=${1:?usage: install_test.sh BUILD}
. "$(dirname "$0")/cli_lib.sh"
P=$T/prefix
MAKE=${MAKE:-make}
CC=${CC:-cc}
CXX=${CXX:-c++}
export LSAN_OPTIONS="${LSAN_OPTIONS:-}"

if ! $MAKE --no-print-directory install BUILD="$B" PREFIX="$P" DESTDIR= SAN="$SAN" ${OPT:+OPT="$OPT"} >"$T/make.log" 2>&1; then
    cat "$T/make.log"
    bad "make install PREFIX=$P"
    echo "install: $pass passed, $fail failed"
    exit 1
fi
ok
PC=$P/lib/pkgconfig/roadsplat.pc
check "roadsplat.pc names the install prefix" grep -qx "prefix=$P" "$PC"
check "roadsplat.pc libdir" grep -qx "libdir=$P/lib" "$PC"
ver=$(sed -n 's/^#define RS_VERSION_\(MAJOR\|MINOR\|PATCH\) *\([0-9]*\).*/\2/p' include/roadsplat.h | paste -sd.)
export PKG_CONFIG_PATH=$P/lib/pkgconfig
check "pkg-config --modversion is the header's version ($ver)" [ "$(pkg-config --modversion roadsplat)" = "$ver" ]

cat > "$T/app.c" <<'C'
#include <roadsplat.h>
#include <roadsplat_experimental.h>
#include <stdio.h>
int main(void)
{
    rs_ctx *ctx;
    rs_dem *dem;
    float z[4 * 3] = { 0 };
    rs_tile_type type;
    int rot;
    size_t nfs = 0;
    /* the GLSL the library ships, and the second header's table */
    if (!rs_gpu_glsl(330, RS_GPU_SHADER_TERRAIN_FRAGMENT, &nfs) || nfs < 1) return 1;
    rs_mask_classify(0xFF, &type, &rot);
    if (type != RS_TILE_INTERIOR) return 1;
    if (rs_ctx_create(NULL, NULL, &ctx) || rs_dem_create(ctx, 4, 3, z, &dem)) return 1;
    printf("%s %u\n", rs_version_string(), rs_dem_width(dem));
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    return 0;
}
C
cp "$T/app.c" "$T/app.cpp"
# both installed headers alone, pedantic, in every C and C++ standard a host may use
printf '#include <roadsplat.h>\n#include <roadsplat_experimental.h>\nint main(void) { return 0; }\n' >"$T/hdr.c"
cp "$T/hdr.c" "$T/hdr.cpp"
for std in c89 c99 c11; do
    check "headers compile alone: -std=$std -pedantic -Werror" $CC -std=$std -pedantic -Wall -Wextra -Werror -I"$P/include" -c "$T/hdr.c" -o "$T/hdr.o"
done
for std in c++11 c++20; do
    check "headers compile alone: -std=$std -pedantic -Werror" $CXX -std=$std -pedantic -Wall -Wextra -Werror -I"$P/include" -c "$T/hdr.cpp" -o "$T/hdr.o"
done
# shellcheck disable=SC2046
if $CC $SAN -std=c99 -Wall -Werror -o "$T/app_c" "$T/app.c" $(pkg-config --cflags --libs roadsplat) -Wl,-rpath,"$P/lib" \
    2>"$T/cc.log"; then
    check "C consumer (shared) runs" [ "$("$T/app_c")" = "$ver 4" ]
    check "C consumer uses the installed shared library" sh -c "ldd '$T/app_c' | grep -q '$P/lib/libroadsplat.so'"
else cat "$T/cc.log"; bad "C consumer builds through pkg-config"; fi
if $CXX $SAN -Wall -Werror -o "$T/app_cxx" "$T/app.cpp" $(pkg-config --cflags --libs roadsplat) -Wl,-rpath,"$P/lib" \
    2>"$T/cxx.log"; then
    check "C++ consumer (shared) runs" [ "$("$T/app_cxx")" = "$ver 4" ]
else cat "$T/cxx.log"; bad "C++ consumer builds through pkg-config"; fi
if $CC $SAN -std=c99 -o "$T/app_static" "$T/app.c" $(pkg-config --cflags roadsplat) \
    "$(pkg-config --variable=libdir roadsplat)/libroadsplat.a" $(pkg-config --static --libs-only-l roadsplat | sed 's/-lroadsplat//') \
    2>"$T/st.log"; then
    check "C consumer (static) runs" [ "$("$T/app_static")" = "$ver 4" ]
else cat "$T/st.log"; bad "C consumer builds against libroadsplat.a"; fi

# The editing host (docs/examples/edits_host.c; docs/embedding.md "Long
# chains"): edits on its thread, whole builds on a worker, rebases; its last
# grid must splat as a fresh build does. The library alone (no OSMesa).
EXE=$(cd "$(dirname "$0")/../docs/examples" && pwd)
# shellcheck disable=SC2046
if $CC $SAN -std=c99 -pedantic -Wall -Wextra -Werror -o "$T/edits_host" "$EXE/edits_host.c" $(pkg-config --cflags --libs roadsplat) \
    -lpthread -Wl,-rpath,"$P/lib" 2>"$T/edits_host.log"; then
    check "example editing host: 40 edits, a rebase, the grid splats as a fresh build" \
        sh -c "'$T/edits_host' '$EXE/dem.pgm' '$EXE/roads.txt' 5 4 40 >'$T/edits_host.out' && grep -q '1 rebases' '$T/edits_host.out'"
    sed 's/^/     /' "$T/edits_host.out"
else cat "$T/edits_host.log"; bad "example editing host builds from the installed library"; fi

# The example hosts (docs/examples/host.c, host.cpp; docs/embedding.md "An
# example host"): built from the installed library through pkg-config, each
# draws on its own OSMesa context and compares its frame with the CPU splat
# (exit 1 past mean 1/255 or p99 8/255). Without OSMesa's pkg-config file they
# are skipped with a line saying so.
EX=$(cd "$(dirname "$0")/../docs/examples" && pwd)
lsan_saved=$LSAN_OPTIONS
if pkg-config --exists osmesa 2>/dev/null; then
    # use_tls=0 for the hosts only (as cli_render_test.sh): kept on, it would
    # report the thread-local error state GDAL keeps for the installed CLI below
    if [ -n "$SAN" ]; then LSAN_OPTIONS="${LSAN_OPTIONS:+$LSAN_OPTIONS:}use_tls=0"; export LSAN_OPTIONS; fi
    # shellcheck disable=SC2046
    if $CC $SAN -std=c99 -pedantic -Wall -Wextra -Werror -o "$T/host" "$EX/host.c" $(pkg-config --cflags --libs roadsplat osmesa) \
        -lm -Wl,-rpath,"$P/lib" 2>"$T/host.log"; then
        check "example host (C): junction frame equals the CPU splat" sh -c "'$T/host' '$EX/junction-dem.pgm' '$EX/junction.txt' 2 0.01 5 >'$T/host.out' && grep -q 'GPU - CPU mean' '$T/host.out'"
        check "example host (C): city frame equals the CPU splat" "$T/host" "$EX/dem.pgm" "$EX/roads.txt" 5 0.01 4
        sed 's/^/     /' "$T/host.out"
    else cat "$T/host.log"; bad "example host (C) builds from the installed library"; fi
    # shellcheck disable=SC2046
    if $CXX $SAN -std=c++11 -pedantic -Wall -Wextra -Werror -o "$T/host_cpp" "$EX/host.cpp" \
        $(pkg-config --cflags --libs roadsplat osmesa) -Wl,-rpath,"$P/lib" 2>"$T/hostxx.log"; then
        check "example host (C++): T junction frame equals the CPU splat" sh -c "'$T/host_cpp' '$EX/network_tee.txt' 41 21 2 16 >'$T/hostxx.out'"
        sed 's/^/     /' "$T/hostxx.out"
    else cat "$T/hostxx.log"; bad "example host (C++) builds from the installed library"; fi
else
    echo "SKIP install: no osmesa.pc (pkg-config): the example hosts docs/examples/host.c and host.cpp are not built"
fi
LSAN_OPTIONS=$lsan_saved

# The installed CLI and its modules.
R=$P/bin/roadsplat
check "installed roadsplat --version" sh -c "'$R' --version | grep -q '$ver'"
check "image module installed" [ -f "$P/lib/roadsplat/roadsplat-image.so" ]
printf 'P2\n5 4\n255\n1 2 3 4 5\n2 3 4 5 6\n3 4 5 6 7\n4 5 6 7 8\n' > "$T/dem.pgm"
printf 'road a width 1\n0.5 0.5\n3.5 2.5\nend\n' > "$T/roads.txt"
check "installed CLI writes a PNG" "$R" --quiet --texels 2 "$T/dem.pgm" "$T/roads.txt" "$T/a.png"
# a 6 x 5 grey PNG (DEMs have one channel)
echo 'iVBORw0KGgoAAAANSUhEUgAAAAYAAAAFCAAAAABDM8I6AAAAKElEQVR4nGNg0AioWHCCgcsoqmnVJQYRm5SeLXcY5Nzypu17BpH6AADYJw4R/ZAYHgAAAABJRU5ErkJggg==' |
    base64 -d >"$T/g.png"
check "installed CLI reads a PNG DEM (image module from $P/lib/roadsplat)" \
    "$R" --quiet --texels 1 "$T/g.png" "$T/roads.txt" "$T/b.png"
mv "$P/lib/roadsplat" "$P/lib/roadsplat.off"
"$R" --quiet --texels 1 "$T/g.png" "$T/roads.txt" "$T/c.png" 2>"$T/err.txt"; rc=$?
check "without the module: exit 1" [ "$rc" = 1 ]
check "without the module: one line naming roadsplat-image.so" sh -c \
    "[ \$(wc -l < '$T/err.txt') = 1 ] && grep -q 'roadsplat-image.so' '$T/err.txt'"
check "without the module: a PGM still works" "$R" --quiet --texels 1 "$T/dem.pgm" "$T/roads.txt" "$T/d.png"
mv "$P/lib/roadsplat.off" "$P/lib/roadsplat"

# install-lib needs neither OpenImageIO nor libdeflate (pkg-config finds nothing here).
L=$T/libonly
if $MAKE --no-print-directory install-lib BUILD="$B" PREFIX="$L" DESTDIR= PKG_CONFIG=false SAN="$SAN" \
    ${OPT:+OPT="$OPT"} >"$T/il.log" 2>&1; then
    check "install-lib: headers, libraries, .pc" sh -c "[ -f '$L/include/roadsplat.h' ] && [ -f '$L/include/roadsplat_experimental.h' ] && [ -f '$L/lib/libroadsplat.a' ] &&
        [ -f '$L/lib/libroadsplat.so' ] && grep -qx 'prefix=$L' '$L/lib/pkgconfig/roadsplat.pc'"
    check "install-lib: no CLI" [ ! -e "$L/bin/roadsplat" ]
else cat "$T/il.log"; bad "make install-lib without OpenImageIO"; fi

if $MAKE --no-print-directory uninstall BUILD="$B" PREFIX="$P" DESTDIR= >"$T/un.log" 2>&1; then
    left=$(find "$P" -type f | wc -l)
    check "make uninstall leaves no files ($left left)" [ "$left" = 0 ]
else cat "$T/un.log"; bad "make uninstall"; fi

# Back to the build's own configuration (PREFIX as given to the outer make, if any),
# so BUILD/roadsplat.pc does not keep naming the temporary prefix.
$MAKE --no-print-directory all BUILD="$B" SAN="$SAN" ${OPT:+OPT="$OPT"} >"$T/back.log" 2>&1 || { cat "$T/back.log"; bad "make all after the test"; }
echo "install: $pass passed, $fail failed"
[ "$fail" = 0 ]
