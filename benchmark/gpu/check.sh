#!/usr/bin/env bash
# The GPU check of the real-size issue: mesh_refiner's EGL-device path on an
# NVIDIA GPU. Runs on the GPU machine from the folder that holds the output
# of make_bundle.sh; writes its logs to LOG_DIR and packs them, after each
# step, into LOG_DIR.tgz (so that a run cut short still returns what it did).
#
#   bash check.sh LOG_DIR
#
# Steps: render_probe at 640x480 and 1920x1440 (stops unless the renderer is
# NVIDIA's); the example three times on all cores and, with taskset, three
# times on two cores, each scored against the ground truth; run_large.sh's
# c (the example's mesh remeshed to 2M faces there, then refined; LARGE_C=0
# skips it); workspaces a and b (if bundled): images rendered again by workspace_synthesizer from the
# bundled options (no COLMAP there: the bundled Poisson mesh stands in for
# its fusion and meshing), refined with the defaults and scored.
# REQUIRE_NVIDIA=0 runs it on any renderer (to try the script on a CPU).
# GL: GLVND's libEGL/libOpenGL must be installed on that machine (Debian's
# libegl1 libopengl0 libglvnd0 unpack there with dpkg -x).
set -u
HERE=$(cd "$(dirname "$0")" && pwd)
LOGS=$(realpath -m "${1:?usage: $(basename "$0") LOG_DIR}")
D=$(mktemp -d)
mkdir -p "$LOGS"
tar xJf "$HERE/bundle.tar.xz" -C "$D" && tar xJf "$HERE/ws.tar.xz" -C "$D" || exit 1
export LD_LIBRARY_PATH=$D/lib QT_QPA_PLATFORM=offscreen LOGS
nvidia_icd=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json  # where GLVND may not look
if [ -f $nvidia_icd ] && ! ls /usr/share/glvnd/egl_vendor.d/ 2>/dev/null | grep -qi nvidia; then
  export __EGL_VENDOR_LIBRARY_FILENAMES=$nvidia_icd
fi
B=$D/bin
T0=$SECONDS
{ nvidia-smi -L; echo "cores: $(nproc)"; uname -r; grep -m1 "model name" /proc/cpuinfo
  ldd "$B/mesh_refiner" | grep "not found"; } 2>&1 | tee "$LOGS/machine.txt"

# timed NAME CMD...: runs CMD with its output in LOGS/NAME.log; appends its
# wall seconds and peak resident memory to LOGS/times.txt.
timed() {
  local name=$1; shift
  python3 - "$name" "$@" <<'PY'
import os, resource, subprocess, sys, time
name, cmd = sys.argv[1], sys.argv[2:]
start = time.time()
with open(os.path.join(os.environ["LOGS"], name + ".log"), "w") as log:
    rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT)
peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
line = f"{name}: rc {rc} wall {time.time() - start:.2f} s peak {peak_mb:.0f} MB"
print(line, flush=True)
with open(os.path.join(os.environ["LOGS"], "times.txt"), "a") as f:
    f.write(line + "\n")
PY
  tar czf "$LOGS.tgz" -C "$LOGS" .
}
score() {  # score NAME MESH WORKSPACE: mesh_evaluator on the observed surface
  timed "$1" "$B/mesh_evaluator" --input_path "$2" --gt_path "$3/ground_truth.ply" \
    --workspace_path "$3/dense"
  tail -1 "$LOGS/$1.log"
}

timed probe "$B/render_probe" --Probe.num_renders 20
timed probe_big "$B/render_probe" --Probe.num_renders 20 --Probe.width 1920 \
  --Probe.height 1440 --Probe.cpu 0
grep -hv "^I " "$LOGS/probe.log" "$LOGS/probe_big.log"
grep -q "^Renderer:" "$LOGS/probe.log" || { echo "no renderer; stopping"; exit 1; }
if [ "${REQUIRE_NVIDIA:-1}" != 0 ] && ! grep -q "^Renderer: NVIDIA" "$LOGS/probe.log"; then
  echo "the renderer is not NVIDIA's; stopping"
  exit 1
fi

EX=$D/example
score example_in "$EX/dense/meshed-poisson.ply" "$EX"
for i in 1 2 3; do
  timed example_all_cores_$i "$B/mesh_refiner" --workspace_path "$EX/dense" \
    --output_path "$D/example_all_cores_$i.ply"
done
grep -E "Renderer:|  time:" "$LOGS/example_all_cores_1.log"
score example_all_cores_out "$D/example_all_cores_1.ply" "$EX"
if command -v taskset > /dev/null; then
  for i in 1 2 3; do
    timed example_2_cores_$i taskset -c 0,1 "$B/mesh_refiner" --workspace_path "$EX/dense" \
      --output_path "$D/example_2_cores_$i.ply"
  done
  grep -E "  time:" "$LOGS/example_2_cores_1.log"
  score example_2_cores_out "$D/example_2_cores_1.ply" "$EX"
fi
echo "example done after $((SECONDS - T0)) s"

# c of run_large.sh: the example's Poisson mesh remeshed to about 2M faces
# there (as run_large.sh does), then refined with the defaults. LARGE_C=0
# skips it.
if [ "${LARGE_C:-1}" != 0 ]; then
  timed c_make_2m "$B/mesh_refiner" --workspace_path "$EX/dense" --output_path "$D/meshed-2m.ply" \
    --Refine.iterations_per_level 0 --Refine.num_levels 1 --Refine.target_edge_px 0.7 \
    --Refine.max_faces 2200000 --Refine.output_subdivisions 0
  timed c_refine "$B/mesh_refiner" --workspace_path "$EX/dense" --input_path "$D/meshed-2m.ply" \
    --output_path "$D/c_refined.ply"
  grep -E "Decimate:|  time:" "$LOGS/c_refine.log"
  score c_in "$D/meshed-2m.ply" "$EX"
  score c_out "$D/c_refined.ply" "$EX"
  echo "c done after $((SECONDS - T0)) s"
fi

for c in a b; do
  [ -d "$D/$c" ] || continue
  timed ${c}_synth "$B/workspace_synthesizer" --config_path "$D/$c/synth.ini" \
    --output_path "$D/$c/ws" --run_colmap 0
  cp "$D/$c/meshed-poisson.ply" "$D/$c/ws/dense/"
  score ${c}_in "$D/$c/ws/dense/meshed-poisson.ply" "$D/$c/ws"
  timed ${c}_refine "$B/mesh_refiner" --workspace_path "$D/$c/ws/dense" \
    --output_path "$D/$c/refined.ply"
  grep -E "Level 0:|  time:" "$LOGS/${c}_refine.log"
  score ${c}_out "$D/$c/refined.ply" "$D/$c/ws"
  echo "$c done after $((SECONDS - T0)) s"
done
cat "$LOGS/times.txt"
