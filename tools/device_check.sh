#!/usr/bin/env bash
# Runs on a GPU machine of the `device` tool (issue 15, part 6), from the kit of tools/device_kit.sh
# (carried as .devkit): the EGL device platform's rows/s at N = 128 and 256 on the built-in Cornell
# box (5k patches) and on a city of 5,000 STL facets, default correction and --correct none, and
# bench_hemicube's bare hemicubes at 1, 2 and 8 worker processes. Every command has its own time
# limit, so the whole check stays within one call (about 5 minutes). Results: the reports and a
# summary table in $OUT (or ./device-out here), and on stdout.
#   run(command="bash tools/device_check.sh", carry=[".devkit"], timeout_s=540)
# Here (llvmpipe), `bash tools/device_check.sh` runs the same steps as a dry run of the script.
set -uo pipefail
cd "$(dirname "$0")/.."
out="${OUT:-$PWD/device-out}"
mkdir -p "$out"
kit=/tmp/ffcube-kit
rm -rf "$kit" && mkdir -p "$kit"
tar -C "$kit" -xJf .devkit/kit.tar.xz || { echo "device_check: no .devkit/kit.tar.xz (tools/device_kit.sh, and carry .devkit)"; exit 1; }
if [ -d /usr/local/nvidia ]; then
  # The device tool's notes: glvnd from the carried packages, and the NVIDIA vendor files.
  for f in .devkit/gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
  export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$out/gpu.txt"
fi
export LD_LIBRARY_PATH="$kit/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
ff="$kit/bin/ffcube"
"$ff" --version 2>&1 | head -1
summary="$out/summary.txt"
printf "%-10s %5s %-8s %9s %9s %9s  %s\n" scene N correct "rows/s" "wall s" "hemis/s" renderer | tee "$summary"
run() {  # scene-name N correct timeout args...
  local name=$1 n=$2 correct=$3 limit=$4
  shift 4
  local tag="${name}_${n}_${correct}" t0 t1
  t0=$(date +%s.%N)
  timeout "$limit" "$ff" formfactors -q "$@" --resolution "$n" --correct "$correct" -o "/tmp/$tag.ffm" \
    --report "$out/$tag.json" >"$out/$tag.log" 2>&1
  local rc=$?
  t1=$(date +%s.%N)
  rm -f "/tmp/$tag.ffm"
  python3 - "$out/$tag.json" "$name" "$n" "$correct" "$rc" "$t0" "$t1" <<'PY' | tee -a "$summary"
import json, sys
path, name, n, correct, rc, t0, t1 = sys.argv[1:]
wall = float(t1) - float(t0)
try:
    r = json.load(open(path))
    print(f"{name:<10} {n:>5} {correct:<8} {r['patches'] / r['seconds']:>9.0f} {wall:>9.2f} "
          f"{r['hemicubes'] / r['seconds']:>9.0f}  {r['backend']}: {r['renderer']}")
except Exception as e:  # a run past its limit or failed: say so, the log is in $OUT
    print(f"{name:<10} {n:>5} {correct:<8} {'-':>9} {wall:>9.2f} {'-':>9}  exit {rc} ({type(e).__name__})")
PY
}
for n in 128 256; do
  for correct in near none; do
    run cornell5k "$n" "$correct" 60 --patches 5000
    run city5k "$n" "$correct" 120 "$kit/city5k.stl" --no-subdivide
  done
done
# Occlusion culling on and off (no longer a command-line option: bench_hemicube compares them in
# code): on a GPU the depth readback per hemicube weighs against fewer triangles drawn.
timeout 90 "$kit/bin/bench_hemicube" --rows 1000 --resolutions 128,256 --threads 1,2,8 2>&1 | tee "$out/bench_hemicube.txt"
echo "device_check: done; $summary"
