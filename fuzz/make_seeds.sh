#!/usr/bin/env bash
# Remakes the seed corpora fuzz/corpus/<harness>/ (see fuzz/README.md): small
# files written by the real `colmap` wherever colmap writes that format, the
# rest by our own writers or by hand. Needs colmap and build/bin (scripts/build.sh).
#
#   bash fuzz/make_seeds.sh          # replaces fuzz/corpus/*/seed_* (other files are kept)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/bin}
COLMAP=${COLMAP:-colmap}
OUT=fuzz/corpus
export QT_QPA_PLATFORM=offscreen
tmp=$(mktemp -d /tmp/mr_fuzz_seeds.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
quiet() { "$@" >"$tmp/last.log" 2>&1 || { cat "$tmp/last.log"; exit 1; }; }

harnesses=(ply obj dense_array fused_vis ini image cameras_bin images_bin points3D_bin
           cameras_txt images_txt points3D_txt)
for h in "${harnesses[@]}"; do
  mkdir -p "$OUT/$h"
  rm -f "$OUT/$h"/seed_*
done
put() { cp "$1" "$OUT/$2/seed_$3"; }  # put FILE HARNESS NAME

# 1. A tiny synthetic workspace (4 views of 64x48): colmap stereo_fusion writes
#    fused.ply and fused.ply.vis, colmap poisson_mesher meshed-poisson.ply
#    (octree depth 4, trim 7, which the synthesizer retries at 3.5: ~200 vertices).
quiet "$BIN/workspace_synthesizer" --output_path "$tmp/ws" --num_views 4 --width 64 --height 48 \
  --num_sparse_points 20 --num_threads 1 --StereoFusion.min_num_pixels 2 \
  --PoissonMeshing.depth 4 --PoissonMeshing.trim 7 --colmap_path "$COLMAP"
ws=$tmp/ws/dense
put "$ws/fused.ply" ply colmap_fused.ply
put "$ws/meshed-poisson.ply" ply colmap_meshed-poisson.ply
put "$ws/fused.ply.vis" fused_vis colmap_fused.ply.vis
put "$tmp/ws/workspace_synthesizer.ini" ini workspace_synthesizer.ini
put "$ws/masks/view_0000.png.png" image mask.png

# 2. The same at 32x24: stereo_fusion fuses no point (an empty fused.ply and
#    .vis, written by colmap); the depth and normal maps are the synthesizer's
#    (COLMAP's format; colmap writes them only in patch_match_stereo, which
#    needs CUDA). The synthesizer reports the empty fusion as an error.
"$BIN/workspace_synthesizer" --output_path "$tmp/ws0" --num_views 2 --width 32 --height 24 \
  --num_sparse_points 20 --num_threads 1 --colmap_path "$COLMAP" >"$tmp/ws0.log" 2>&1 || true
ws0=$tmp/ws0/dense
[ -f "$ws0/fused.ply.vis" ] || { cat "$tmp/ws0.log"; exit 1; }
put "$ws0/fused.ply" ply colmap_fused_empty.ply
put "$ws0/fused.ply.vis" fused_vis colmap_fused_empty.ply.vis
put "$ws0/stereo/depth_maps/view_0000.png.geometric.bin" dense_array depth_32x24.bin
put "$ws0/stereo/normal_maps/view_0000.png.geometric.bin" dense_array normal_32x24.bin

# 3. Sparse models written by colmap model_converter: the synthesizer's model
#    to TXT, that TXT back to BIN, and the points as PLY.
mkdir -p "$tmp/txt" "$tmp/bin"
quiet "$COLMAP" model_converter --input_path "$ws/sparse" --output_path "$tmp/txt" --output_type TXT
quiet "$COLMAP" model_converter --input_path "$tmp/txt" --output_path "$tmp/bin" --output_type BIN
quiet "$COLMAP" model_converter --input_path "$tmp/bin" --output_path "$tmp/points3D.ply" \
  --output_type PLY
put "$tmp/points3D.ply" ply colmap_points3D.ply
for f in cameras images points3D; do
  put "$tmp/txt/$f.txt" "${f}_txt" colmap_$f.txt
  put "$tmp/bin/$f.bin" "${f}_bin" colmap_$f.bin
done

# 4. Every camera model colmap 3.8 knows, one camera each, read and written by
#    colmap (model_converter TXT -> BIN -> TXT).
mkdir -p "$tmp/models_in" "$tmp/models_bin" "$tmp/models_txt"
cat >"$tmp/models_in/cameras.txt" <<'EOF'
1 SIMPLE_PINHOLE 64 48 50 32 24
2 PINHOLE 64 48 50 51 32 24
3 SIMPLE_RADIAL 64 48 50 32 24 0.01
4 RADIAL 64 48 50 32 24 0.01 -0.002
5 OPENCV 64 48 50 51 32 24 0.01 -0.002 0.001 0.0005
6 OPENCV_FISHEYE 64 48 50 51 32 24 0.01 -0.002 0.001 0.0005
7 FULL_OPENCV 64 48 50 51 32 24 0.01 -0.002 0.001 0.0005 0.0001 0.0002 0.0003 0.0004
8 FOV 64 48 50 51 32 24 0.9
9 SIMPLE_RADIAL_FISHEYE 64 48 50 32 24 0.01
10 RADIAL_FISHEYE 64 48 50 32 24 0.01 -0.002
11 THIN_PRISM_FISHEYE 64 48 50 51 32 24 0.01 -0.002 0.001 0.0005 0.0001 0.0002 0.0003 0.0004
EOF
: >"$tmp/models_in/images.txt"
: >"$tmp/models_in/points3D.txt"
quiet "$COLMAP" model_converter --input_path "$tmp/models_in" --output_path "$tmp/models_bin" \
  --output_type BIN
quiet "$COLMAP" model_converter --input_path "$tmp/models_bin" --output_path "$tmp/models_txt" \
  --output_type TXT
put "$tmp/models_bin/cameras.bin" cameras_bin colmap_all_models.bin
put "$tmp/models_txt/cameras.txt" cameras_txt colmap_all_models.txt

# 5. Images written by colmap image_undistorter: the workspace's images under
#    .jpg names and with a slightly distorted camera (OPENCV, k1 = 0.01), so
#    that colmap resamples them and writes JPEGs; then the same as PNGs. Its
#    undistorted model (BIN, image names *.jpg) is a seed too.
for ext in jpg png; do
  mkdir -p "$tmp/dist_$ext/images" "$tmp/dist_$ext/sparse"
  for f in "$ws"/images/*.png; do cp "$f" "$tmp/dist_$ext/images/$(basename "$f" .png).$ext"; done
  sed "s/\.png/.$ext/" "$tmp/txt/images.txt" >"$tmp/dist_$ext/sparse/images.txt"
  sed -E 's/^([0-9]+) PINHOLE (.*)$/\1 OPENCV \2 0.01 0 0 0/' "$tmp/txt/cameras.txt" \
    >"$tmp/dist_$ext/sparse/cameras.txt"
  cp "$tmp/txt/points3D.txt" "$tmp/dist_$ext/sparse/"
  quiet "$COLMAP" image_undistorter --image_path "$tmp/dist_$ext/images" \
    --input_path "$tmp/dist_$ext/sparse" --output_path "$tmp/und_$ext"
  put "$tmp/und_$ext/images/view_0000.$ext" image colmap_undistorted.$ext
  put "$tmp/und_$ext/images/view_0003.$ext" image colmap_undistorted_2.$ext
done
put "$tmp/und_jpg/sparse/cameras.bin" cameras_bin colmap_undistorted_cameras.bin
put "$tmp/und_jpg/sparse/images.bin" images_bin colmap_undistorted_images.bin

# 6. Option files: ours (mesh_refiner's, whose options the ini harness
#    registers) and colmap's project file (its keys are refused as unknown).
quiet "$BIN/mesh_refiner" --write_config "$tmp/mesh_refiner.ini"
put "$tmp/mesh_refiner.ini" ini mesh_refiner.ini
quiet "$COLMAP" project_generator --output_path "$tmp/project.ini"
put "$tmp/project.ini" ini colmap_project.ini

# 7. OBJ (colmap writes no OBJ mesh): the Poisson mesh through our OBJ writer
#    (mesh_denoiser, one Laplacian pass), and the other forms by hand.
quiet "$BIN/mesh_denoiser" --input_path "$ws/meshed-poisson.ply" --output_path "$tmp/poisson.obj" \
  --Denoise.method laplacian --Denoise.laplacian_iterations 1
put "$tmp/poisson.obj" obj meshed-poisson.obj
cat >"$OUT/obj/seed_forms.obj" <<'EOF'
# v, v with w, vertex colours, vt/vn, every face form, negative indices, a quad
mtllib none.mtl
o thing
v 0 0 0 1 0 0
v 1 0 0 0 1 0
v 0 1 0 0 0 1
v 0 0 1 0.5 0.5 0.5
vt 0 0
vt 1 0
vt 0 1
vn 0 0 1
vn 0 1 0
g part
usemtl red
s off
f 1 3 2
f 1/1 2/2 4/3
f 1//1 4//2 3//1
f -4/1/1 -3/2/2 -1/3/1
f 1 2 3 4
l 1 2
EOF
cat >"$OUT/ply/seed_ascii.ply" <<'EOF'
ply
format ascii 1.0
comment a tetrahedron with normals, colours and a skipped element
element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
property uchar red
property uchar green
property uchar blue
element face 4
property list uchar int vertex_indices
element edge 1
property int vertex1
property int vertex2
end_header
0 0 0 0 0 1 255 0 0
1 0 0 0 0 1 0 255 0
0 1 0 0 0 1 0 0 255
0 0 1 0 0 1 9 9 9
3 0 2 1
3 0 1 3
3 0 3 2
4 1 2 3 0
0 1
EOF
du -sh "$OUT"
for h in "${harnesses[@]}"; do
  printf '%-14s %3d files %7d bytes\n' "$h" "$(ls "$OUT/$h" | wc -l)" "$(cat "$OUT/$h"/* | wc -c)"
done
