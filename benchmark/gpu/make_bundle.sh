#!/usr/bin/env bash
# Packs the built programs, the shared libraries they load, and the
# workspaces of the GPU check (the example, run_large.sh's a and b) into
# OUT_DIR, for a GPU machine that has an NVIDIA driver but none of the
# project's Debian packages (see README.md beside this file).
#
#   bash benchmark/gpu/make_bundle.sh OUT_DIR EXAMPLE_WS [LARGE_A_WS [LARGE_B_WS]]
#
# Writes OUT_DIR/bundle.tar.xz (bin/, lib/), OUT_DIR/ws.tar.xz and a copy of
# check.sh. A workspace argument is a workspace_synthesizer output folder.
# Of a and b only the Poisson mesh and the synthesizer's options travel: the
# check renders their images again there with the same options and seed.
#
# libopencv_imgcodecs is linked with BIND_NOW against GDAL and GDCM, whose
# dependency closure is 150 MB; it calls GDALAllRegister when it builds its
# decoder list and nothing else of either unless asked for a GDAL or DICOM
# file. Stand-ins that define the 25 imported functions (returning 0, i.e.
# "cannot open") replace them, and the bundle stays at about 15 MB.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=$(realpath -m "${1:?usage: $(basename "$0") OUT_DIR EXAMPLE_WS [A_WS [B_WS]]}")
EXAMPLE=$(realpath "${2:?example workspace}")
A=${3:+$(realpath "$3")}
B=${4:+$(realpath "$4")}
BIN=${BIN:-$PWD/build/bin}
STAGE=$(mktemp -d)
trap 'rm -rf "$STAGE"' EXIT
mkdir -p "$OUT" "$STAGE/bin" "$STAGE/lib" "$STAGE/ws"
ldconfig -p > "$STAGE/ldcache"
lib_path() { awk -v l="$1" '$1 == l && /x86-64/{print $NF; exit}' "$STAGE/ldcache"; }
programs="mesh_refiner workspace_synthesizer mesh_evaluator render_probe"
for p in $programs; do cp "$BIN/$p" "$STAGE/bin/" && strip "$STAGE/bin/$p"; done

# The stand-ins, from the symbols imgcodecs takes from each library.
imgcodecs=$(awk '/libopencv_imgcodecs\.so\.[0-9]+ .*x86-64/{print $NF; exit}' "$STAGE/ldcache")
stubbed=$(readelf -d "$imgcodecs" | sed -n 's/.*NEEDED.*\[\(lib\(gdal\|gdcm\)[^]]*\)\].*/\1/p')
nm -D --undefined-only "$imgcodecs" | awk '{print $2}' | sort > "$STAGE/undefined"
for lib in $stubbed; do
  path=$(lib_path "$lib")
  nm -D --defined-only "$path" | awk 'NF == 3 {print $3}' | sort | comm -12 - "$STAGE/undefined" |
    awk '{printf "long stub_%d(void) __asm__(\"%s\");\nlong stub_%d(void) { return 0; }\n", NR, $1, NR}' \
      > "$STAGE/$lib.c"
  gcc -shared -fPIC -o "$STAGE/lib/$lib" "$STAGE/$lib.c" -Wl,-soname,"$lib"
done

# Every other library the programs need, recursively, but the C and C++
# runtimes and GLVND's GL/EGL (the machine's own, with its NVIDIA driver).
skip='^(libc|libm|libpthread|libdl|librt|ld-linux-x86-64|libstdc\+\+|libgcc_s|libEGL|libOpenGL|libGLdispatch|libGLX|libGL)\.so'
declare -A seen
queue=()
for p in $programs; do queue+=("$BIN/$p"); done
while [ ${#queue[@]} -gt 0 ]; do
  file=${queue[0]}; queue=("${queue[@]:1}")
  for need in $(readelf -d "$file" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
    [[ $need =~ $skip ]] && continue
    [ -n "${seen[$need]:-}" ] && continue
    seen[$need]=1
    [ -f "$STAGE/lib/$need" ] && continue  # a stand-in
    path=$(lib_path "$need")
    [ -n "$path" ] || { echo "not found: $need (needed by $file)" >&2; exit 1; }
    cp -L "$path" "$STAGE/lib/$need"
    queue+=("$path")
  done
done
tar cJf "$OUT/bundle.tar.xz" -C "$STAGE" bin lib

mkdir -p "$STAGE/ws/example/dense"
cp "$EXAMPLE/ground_truth.ply" "$STAGE/ws/example/"
cp -r "$EXAMPLE/dense/images" "$EXAMPLE/dense/sparse" "$EXAMPLE/dense/meshed-poisson.ply" \
  "$STAGE/ws/example/dense/"
[ -d "$EXAMPLE/dense/masks" ] && cp -r "$EXAMPLE/dense/masks" "$STAGE/ws/example/dense/"
for c in a b; do
  ws=$([ "$c" = a ] && echo "$A" || echo "$B")
  [ -n "$ws" ] || continue
  mkdir -p "$STAGE/ws/$c"
  cp "$ws/dense/meshed-poisson.ply" "$STAGE/ws/$c/"
  cp "$ws/workspace_synthesizer.ini" "$STAGE/ws/$c/synth.ini"  # its options and seed
done
tar cJf "$OUT/ws.tar.xz" -C "$STAGE/ws" .
cp benchmark/gpu/check.sh "$OUT/"
du -h "$OUT"/*.tar.xz
