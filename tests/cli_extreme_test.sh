#!/bin/sh
# CLI on a float32 TIFF with NaN (nodata) samples, written byte by byte here
# (no image tools needed): the splat and `roadsplat mesh` succeed, produce
# output, and no NaN reaches the OBJ. Usage: sh tests/cli_extreme_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_extreme_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"

byte() { printf "\\$(printf '%03o' "$1")"; }
le16() { byte $(($1 & 255)); byte $((($1 >> 8) & 255)); }
le32() { le16 $(($1 & 65535)); le16 $((($1 >> 16) & 65535)); }
entry() { le16 "$1"; le16 "$2"; le32 1; if [ "$2" = 3 ]; then le16 "$3"; le16 0; else le32 "$3"; fi; } # tag type value
W=6; H=5
{
    printf 'II'; le16 42; le32 8
    le16 10 # little-endian baseline TIFF, one strip, uncompressed, float32 (SampleFormat 3)
    entry 256 3 $W; entry 257 3 $H; entry 258 3 32; entry 259 3 1; entry 262 3 1
    entry 273 4 136; entry 277 3 1; entry 278 3 $H; entry 279 4 $((W * H * 4)); entry 339 3 3
    le32 0; le16 0 # next IFD; pad to offset 136
    i=0
    while [ $i -lt $((W * H)) ]; do
        case $((i % 7)) in
        3) le32 2143289344 ;;   # 0x7FC00000 quiet NaN
        5) le32 1092616192 ;;   # 10.0
        *) le32 $((1065353216 + i * 65536)) ;; # 1.0 and a little more per sample
        esac
        i=$((i + 1))
    done
} > "$T/nan.tif"
check "TIFF is 256 bytes" test "$(wc -c < "$T/nan.tif")" -eq 256
printf 'road a width 1.5\n0.5 0.5\n4.5 3.5\nend\n' > "$T/roads.txt"
check "splat of a NaN TIFF exits 0" "$BIN" --texels 4 "$T/nan.tif" "$T/roads.txt" "$T/out.png"
check "splat wrote a PNG" test -s "$T/out.png"
check "mesh of a NaN TIFF exits 0" "$BIN" mesh --max-error 0 "$T/nan.tif" "$T/m.obj"
check "mesh has vertices and faces" sh -c "grep -q '^v ' '$T/m.obj' && grep -q '^f ' '$T/m.obj'"
check "no NaN or inf in the OBJ" sh -c "! grep -qiE 'nan|inf' '$T/m.obj'"
check "mesh vertices within the 30 samples" test "$(grep -c '^v ' "$T/m.obj")" -le 30
echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
