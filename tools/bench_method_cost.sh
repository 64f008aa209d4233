#!/usr/bin/env bash
# The method by measured cost (issue 40 part 4; docs/accuracy.md, "The method by cost"): calibrate
# this machine, then on generated cities (one patch a facet) run --method hemicube, --method
# raycast, and --method auto with the built-in model and with the measured one, at the default
# tolerance; print each run's CPU seconds (user + sys of ffcube and its workers) and what auto
# chose, with the two costs it weighed.
#   bash tools/bench_method_cost.sh [FACETS...]        (default 1000 5000)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${FFCUBE_BUILD_DIR:-build}"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
"$build/ffcube" calibrate -q -o "$dir/costs.json"
python3 -c "import json,sys; m=json.load(open(sys.argv[1])); print('calibrate: ' + ', '.join(f'{k} {m[k]:.4g}' for k in ('pixel_ns','piece_ns','ray_ns','cpu_scale')))" "$dir/costs.json"
for facets in "${@:-1000 5000}"; do
  for n in $facets; do
    /usr/bin/python3 tools/gen_city.py "$dir/c$n.stl" --binary --triangles "$n" --seed 1 >/dev/null
    for run in "hemicube|--method hemicube" "raycast|--method raycast" "auto built-in|" "auto measured|--cost-model $dir/costs.json"; do
      name="${run%%|*}"; args="${run#*|}"
      /usr/bin/time -f "%U %S" -o "$dir/t" "$build/ffcube" formfactors "$dir/c$n.stl" --no-subdivide -q $args \
        -o "$dir/F.ffm" --report "$dir/r.json" 2>/dev/null
      python3 - "$dir/t" "$dir/r.json" "$n" "$name" <<'PY'
import json, sys
u, s = map(float, open(sys.argv[1]).read().split()[-2:])
r = json.load(open(sys.argv[2]))
c = r.get("method_cost", {})
costs = f"; a row by hemicube {c['scene_row_hemicube_ms']:.3g} ms, by rays {c['scene_row_rays_ms']:.3g} ms" if c else ""
print(f"{sys.argv[3]} facets, {sys.argv[4]}: {u + s:.1f} CPU-s, {r['method']}{costs}")
PY
    done
  done
done
