#!/usr/bin/env bash
# Geometry-heavy scenes (issue 15, part 3): a CAD/GIS-like STL city from tools/gen_city.py, one
# patch per facet (--no-subdivide), timed end to end with the default correction. Prints the
# method that ran (--method auto: the ray caster on a mesh of 1,000 facets or more), wall
# and CPU seconds (the process and its worker processes), rows/s, the rows built from
# sub-hemicubes (and of those, the rows an occluder touches that were ray-cast: --fine-rows), the
# refused near pairs, and the pieces classified one by one against all
# pieces × hemicubes (what the BVH left out). BASELINE=path/to/ffcube runs an older build on
# the same city in the same sitting, for a ratio.
#   bash tools/bench_city.sh [TRIANGLES] [RESOLUTION] [SEED]     (default 22881 256 1; GROUND=lots|grid)
# ARGS="--sub-hemicube-k 1" adds options to the current build's run (not the baseline's).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${FFCUBE_BUILD_DIR:-build}"
triangles="${1:-22881}"
resolution="${2:-256}"
seed="${3:-1}"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
python3 tools/gen_city.py "$dir/city.stl" --binary --triangles "$triangles" --seed "$seed" --ground "${GROUND:-lots}" 2>/dev/null
echo "city: $triangles triangles (seed $seed, ground ${GROUND:-lots}), N=$resolution, $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
printf "%-10s %-9s %8s %8s %8s %10s %9s %14s %14s %9s\n" build method "wall (s)" "cpu (s)" "rows/s" "sub-hemi" "ray-cast" "refused pairs" "pieces tested" "occluded"
for which in ${BASELINE:+baseline} current; do
  bin="$build/ffcube"
  [ "$which" = baseline ] && bin="$BASELINE"
  /usr/bin/time -f "%e %U %S" -o "$dir/$which.time" "$bin" formfactors -q "$dir/city.stl" --no-subdivide \
    --resolution "$resolution" -o "$dir/$which.ffm" --report "$dir/$which.json" ${ARGS:+$([ "$which" = current ] && echo $ARGS)}
  python3 - "$dir/$which.time" "$dir/$which.json" "$which" <<'PY'
import json, sys
wall, user, system = map(float, open(sys.argv[1]).read().split()[-3:])
r = json.load(open(sys.argv[2]))
c, lo = r.get("corrections", {}), r.get("left_out", {})
tested = lo.get("pieces_tested")
share = f"{tested / lo['pieces_considered']:.1%}" if tested is not None else "all"
occ = sum(lo.get("pieces_occluded_per_face", {}).values())
drawn = sum(r.get("drawn", {}).get("pieces_per_face", {}).values())
occluded = f"{occ / (occ + drawn):.1%}" if "pieces_occluded_per_face" in lo and occ + drawn else "-"
cast = r.get("fine_rows", {}).get("cast", 0)
print(f"{sys.argv[3]:<10} {r.get('method', '?'):<9} {wall:>8.1f} {user + system:>8.1f} {r['patches'] / wall:>8.1f} {c.get('rows_sub_hemicubes', 0):>10} {cast:>9}"
      f" {c.get('pairs_refused_possibly_occluded', 0):>14} {share:>14} {occluded:>9}")
PY
done
