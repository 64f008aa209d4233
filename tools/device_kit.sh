#!/usr/bin/env bash
# Packs what a GPU machine of the `device` tool needs to run this build (issue 15, part 6: rows/s on
# the EGL device platform), into .devkit/ (git-ignored), for tools/device_check.sh to run there.
# That machine is not Debian 12 and fetches nothing: it gets this build's ffcube and bench_hemicube
# (stripped), every shared library they load besides glibc's and libstdc++'s (from `ldd`; GL itself is
# dlopened: the machine's NVIDIA driver through glvnd), packed as .devkit/kit.tar.xz, and Debian's
# glvnd packages in .devkit/gl (the device tool's notes: unpack them with dpkg -x there).
#   bash tools/device_kit.sh                  (after FFCUBE_BUILD_ALL=1 bash tools/setup.sh)
# Then, on a task that is lent a machine, one call of the device tool:
#   run(command="bash tools/device_check.sh", carry=[".devkit"], timeout_s=540)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${FFCUBE_BUILD_DIR:-build}"
kit=.devkit
for f in "$build/ffcube" "$build/tools/bench_hemicube"; do
  [ -x "$f" ] || { echo "device_kit: $f is missing: build first (FFCUBE_BUILD_ALL=1 bash tools/setup.sh)" >&2; exit 1; }
done
rm -rf "$kit"
mkdir -p "$kit/stage/bin" "$kit/stage/lib" "$kit/gl"
strip -o "$kit/stage/bin/ffcube" "$build/ffcube"
strip -o "$kit/stage/bin/bench_hemicube" "$build/tools/bench_hemicube"
# Libraries besides the C and C++ runtimes (the machine's own are newer: Debian 12's binaries run on them).
ldd "$build/ffcube" "$build/tools/bench_hemicube" | awk '$3 ~ /^\// {print $3}' | sort -u |
  grep -Ev '/(libc|libm|libdl|libpthread|librt|libgcc_s|libstdc\+\+)\.so' |
  while read -r lib; do cp -L "$lib" "$kit/stage/lib/"; done
python3 tools/gen_city.py --triangles 5000 --seed 1 "$kit/stage/city5k.stl" >/dev/null 2>&1
tar -C "$kit/stage" -cJf "$kit/kit.tar.xz" .
rm -rf "$kit/stage"
# glvnd's loaders, as the device tool's notes say (Debian's packages, amd64).
lists=/tmp/ffcube-devkit-apt
mkdir -p "$lists/partial"
o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 "-oDir::State::Lists=$lists")
apt-get "${o[@]}" update >/dev/null
(cd "$kit/gl" && apt-get "${o[@]}" download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2 >/dev/null)
du -sh "$kit" "$kit"/*
size=$(du -sk "$kit" | cut -f1)
[ "$size" -lt $((60 * 1024)) ] || { echo "device_kit: $kit is $size KiB, over what a call carries (64 MiB with the tree)" >&2; exit 1; }
echo "device_kit: ready; carry .devkit and run tools/device_check.sh there"
