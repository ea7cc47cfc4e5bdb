#!/usr/bin/env bash
# Regenerates the seed corpus of the fuzz harnesses under fuzz/corpus/<harness>/ (checked in;
# rerun after changing a harness's input layout). Needs oiiotool (openimageio-tools) and
# python3. Deterministic: a fixed DateTime and no software name in the images.
#   fuzz/make_corpus.sh
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
[ $# -eq 0 ] || { echo "make_corpus.sh: takes no arguments" >&2; exit 2; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# ---- image_loader: byte 0 = extension index, byte 1 = options, then the file ---------------
# Extension index (image_loader_fuzzer.cpp kExtensions): 0 png, 1 tga, 2 tif, 3 exr, 4 jpg,
# 5 hdr, 6 bmp, 7 none. Options: bit 7 cone-map loader; height loader: bits 0-2 channel
# (0 auto, 1 R, 2 G, 3 B, 4 A), bit 3 stores depth; cone loader: bits 0-2 channel + 1
# (0 = all four), bit 3 quad, bit 4 expect 4x4.
img="$here/corpus/image_loader"
rm -rf "$img"
mkdir -p "$img"
oi() { oiiotool --nosoftwareattrib "$@"; }
seed() {  # seed NAME EXT_INDEX OPTIONS FILE
    { printf "\\x$(printf %02x "$2")\\x$(printf %02x "$3")"; cat "$4"; } >"$img/$1"
}
grad() { echo "--pattern fill:top=0:bottom=1 $1 $2"; }

oi $(grad 4x4 1) -d uint8 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/g8.png"
oi $(grad 4x4 1) -d uint16 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/g16.png"
oi $(grad 4x4 3) -d uint8 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/rgb8.png"
oi $(grad 4x4 4) -d uint8 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/rgba8.png"
oi $(grad 3x5 2) -d uint8 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/ga8.png"
oi $(grad 4x4 1) -d uint8 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/g8.tga"
oi $(grad 4x4 4) -d uint8 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' --attrib compression rle -o "$tmp/rgba8rle.tga"
oi $(grad 4x4 1) -d float --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/f32.tif"
oi $(grad 4x4 2) -d uint16 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' --compression zip -o "$tmp/g16a.tif"
oi $(grad 4x4 1) -d half --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' --compression none -o "$tmp/h.exr"
oi $(grad 4x4 4) -d float --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' --compression zip -o "$tmp/rgbaf.exr"
oi --pattern black 4x4 1 -d float --powc -1 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' --compression none -o "$tmp/inf.exr"
oi --pattern constant:color=2 4x4 1 -d float --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' --compression none -o "$tmp/two.exr"
oi $(grad 8x8 1) -d uint8 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/g8.jpg"
oi $(grad 4x4 3) --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/rgb.hdr"
oi $(grad 4x4 3) -d uint8 --eraseattrib '.*' --attrib DateTime '2000:01:01 00:00:00' -o "$tmp/rgb8.bmp"

seed png_gray8_auto 0 0x00 "$tmp/g8.png"
seed png_gray16_depth 0 0x08 "$tmp/g16.png"
seed png_rgb8_auto_no_alpha 0 0x00 "$tmp/rgb8.png"
seed png_rgb8_r 0 0x01 "$tmp/rgb8.png"
seed png_rgba8_a 0 0x04 "$tmp/rgba8.png"
seed png_ga8_auto 0 0x00 "$tmp/ga8.png"
seed png_ga8_b_missing 0 0x03 "$tmp/ga8.png"
seed tga_gray8 1 0x00 "$tmp/g8.tga"
seed tga_rgba8_rle_g 1 0x02 "$tmp/rgba8rle.tga"
seed tif_float 2 0x00 "$tmp/f32.tif"
seed tif_gray16_alpha_zip 2 0x04 "$tmp/g16a.tif"
seed exr_half 3 0x00 "$tmp/h.exr"
seed exr_rgba_float_zip 3 0x0b "$tmp/rgbaf.exr"
seed exr_inf 3 0x00 "$tmp/inf.exr"
seed exr_out_of_range 3 0x00 "$tmp/two.exr"
seed jpg_gray8 4 0x00 "$tmp/g8.jpg"
seed hdr_rgb 5 0x01 "$tmp/rgb.hdr"
seed bmp_rgb8 6 0x02 "$tmp/rgb8.bmp"
seed noext_png 7 0x00 "$tmp/g8.png"
seed noext_exr 7 0x00 "$tmp/h.exr"
seed png_as_tga 1 0x00 "$tmp/g8.png"
# Cone-map loader (bit 7).
seed cone_png_rgba_all_4x4 0 0x90 "$tmp/rgba8.png"
seed cone_tga_rgba_b 1 0x83 "$tmp/rgba8rle.tga"
seed cone_exr_rgba_quad 3 0x88 "$tmp/rgbaf.exr"
seed cone_png_gray_wrong_size 0 0x91 "$tmp/g16.png"
seed cone_exr_inf 3 0x81 "$tmp/inf.exr"
# Truncated and empty files.
for f in g8.png rgba8.png f32.tif h.exr rgbaf.exr rgba8rle.tga g8.jpg; do
    n=$(stat -c %s "$tmp/$f")
    head -c $((n / 2)) "$tmp/$f" >"$tmp/half_$f"
    head -c $((n - 4)) "$tmp/$f" >"$tmp/short_$f"
done
seed trunc_half_png 0 0x00 "$tmp/half_g8.png"
seed trunc_short_png_rgba 0 0x04 "$tmp/short_rgba8.png"
seed trunc_half_tif 2 0x00 "$tmp/half_f32.tif"
seed trunc_short_tif 2 0x00 "$tmp/short_f32.tif"
seed trunc_half_exr 3 0x00 "$tmp/half_h.exr"
seed trunc_short_exr_zip 3 0x00 "$tmp/short_rgbaf.exr"
seed trunc_half_tga_rle 1 0x02 "$tmp/half_rgba8rle.tga"
seed trunc_short_jpg 4 0x00 "$tmp/short_g8.jpg"
: >"$tmp/empty"
seed empty_png 0 0x00 "$tmp/empty"
seed empty_noext 7 0x00 "$tmp/empty"
printf 'not an image\n' >"$tmp/text"
seed text_as_exr 3 0x00 "$tmp/text"

# Headers that claim a size: python3 builds them (PNG IHDR with a valid CRC; a TGA header,
# at most 65535 a side; an EXR whose dataWindow is patched): 2048 (allowed, 8-bit: 4 MB), 16385
# (one over kMaxImageSide) and 100000 (what the loader once allocated ~10-40 GB for).
claim() {  # claim W H OUTPREFIX
    python3 - "$1" "$2" "$3" "$tmp/h.exr" <<'EOF'
import struct, sys, zlib
w, h, out, exr = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4]
def chunk(t, d):
    return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) +
       chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + chunk(b"IEND", b""))
open(out + "_png", "wb").write(b"\x00\x00" + png)
tw, th = min(w, 65535), min(h, 65535)
tga = struct.pack("<BBBHHBHHHHBB", 0, 0, 3, 0, 0, 0, 0, 0, tw, th, 8, 0) + b"\x80" * 16
open(out + "_tga", "wb").write(b"\x01\x00" + tga)
data = bytearray(open(exr, "rb").read())
key = b"dataWindow\x00box2i\x00" + struct.pack("<i", 16)
i = data.index(key) + len(key)
data[i:i + 16] = struct.pack("<iiii", 0, 0, w - 1, h - 1)
open(out + "_exr", "wb").write(b"\x03\x00" + bytes(data))
EOF
}
for n in 2048 16385 100000; do claim "$n" "$n" "$img/claims_$n"; done

# ---- set_params: line 1 the method, then key=value settings --------------------------------
sp="$here/corpus/set_params"
rm -rf "$sp"
mkdir -p "$sp"
t() { printf '%s' "$2" >"$sp/$1"; }
t relief_ok $'relief\nlinear_steps=16\nrefine_steps=4'
t secant_ok $'secant\nlinear_steps=8\nrefine_steps=3\nsecant_tolerance=0.001'
t linear_budget $'linear\nbudget=100\nearly_exit=0'
t interval_ok $'interval\nrefine_steps=6'
t pom_ok $'pom\nlinear_steps=32'
t defaults_only 'relief'
t unknown_method $'cone\nlinear_steps=4'
t unknown_key $'relief\nsteps=4'
t not_integer $'relief\nlinear_steps=3.5'
t out_of_range $'linear\nlinear_steps=1e9'
t negative $'interval\nrefine_steps=-1'
t not_a_number $'secant\nsecant_tolerance=abc'
t nan $'relief\nlinear_steps=nan'
t inf $'relief\nlinear_steps=inf'
t hex $'relief\nlinear_steps=0x10'
t empty_value $'relief\nlinear_steps='
t empty_key $'relief\n=5'
t no_equals $'relief\nlinear_steps'
t two_equals $'relief\nlinear_steps=4=5'
t repeated $'relief\nlinear_steps=4\nlinear_steps=8'
t spaces $'relief\n linear_steps = 4'
t crlf $'relief\r\nlinear_steps=4\r'
t empty_method $'\nlinear_steps=4'
t huge_digits $'linear\nbudget=99999999999999999999999999999999999999'
t denormal $'secant\nsecant_tolerance=1e-320'

# ---- render_options: the arguments after `reliefsim render`, one per line ------------------
ro="$here/corpus/render_options"
rm -rf "$ro"
mkdir -p "$ro"
r() { printf '%s' "$2" >"$ro/$1"; }
r defaults $'--out\nout'
r readme_relief $'--map\nbuiltin:shapes:64\n--method\nrelief\n--size\n512x512\n--view-angle\n60\n--set\nlinear_steps=16\n--set\nrefine_steps=4\n--out\nout/relief16'
r readme_file_map $'--map\nrock.png\n--map-channel\nA\n--map-stores\ndepth\n--method\nsecant\n--out\nout/rock'
r every_option $'--map\nbuiltin:noise:32\n--map-channel\nR\n--map-stores\ndepth\n--method\ninterval\n--set\nrefine_steps=5\n--size\n64x48\n--view-angle\n45\n--azimuth\n30\n--distance\n2\n--fov\n50\n--depth-scale\n0.2\n--tiling\n2\n--filter\nnearest\n--wrap\nclamp\n--texture-format\nr8\n--threads\n2\n--iterations-scale\n0:32\n--fetches-scale\n1:128\n--quiet\n--out\no'
r equals_form $'--size=256x256\n--view-angle=30\n--method=pom\n--out=o'
r bad_size $'--size\n512\n--out\no'
r bad_size_x $'--size\n0x10\n--out\no'
r huge_size $'--size\n99999x99999\n--out\no'
r size_overflow $'--size\n4294967296x1\n--out\no'
r size_negative $'--size\n-1x-1\n--out\no'
r view_angle_90 $'--view-angle\n90\n--out\no'
r view_angle_nan $'--view-angle\nnan\n--out\no'
r depth_scale_zero $'--depth-scale\n0\n--out\no'
r fov_inf $'--fov\ninf\n--out\no'
r bad_filter $'--filter\ncubic\n--out\no'
r bad_wrap $'--wrap\nmirror\n--out\no'
r bad_format $'--texture-format\nrgba8\n--out\no'
r bad_scale $'--iterations-scale\n64:0\n--out\no'
r scale_garbage $'--fetches-scale\n1:2:3\n--out\no'
r bad_method $'--method\ncone\n--out\no'
r bad_set $'--set\nlinear_steps=0\n--out\no'
r bad_channel $'--map-channel\nX\n--out\no'
r bad_stores $'--map-stores\nheights\n--out\no'
r builtin_unknown $'--map\nbuiltin:nope\n--out\no'
r builtin_bad_size $'--map\nbuiltin:shapes:12x\n--out\no'
r builtin_zero $'--map\nbuiltin:steps:0\n--out\no'
r builtin_analytic $'--map\nbuiltin:ramp:8\n--out\no'
r missing_out $'--method\nrelief'
r unknown_option $'--bogus\n1\n--out\no'
r missing_value $'--out'
r help $'--help'
r threads_negative $'--threads\n-3\n--out\no'
r number_garbage $'--azimuth\n1e999\n--distance\nabc\n--out\no'
r positional $'extra\n--out\no'
echo "corpus: $(find "$here/corpus" -type f | wc -l) files, $(du -sh "$here/corpus" | cut -f1)"
