#!/usr/bin/env bash
# The encoder at scale (issue 37's figures): synthetic scans of the sizes
# given (stipple-make-scan: binary PLY with normals, LAS without), then every
# scan in ../shared/data, each encoded with `stipple encode --json`: wall
# seconds, CPU seconds, points per second (wall and per CPU-second), peak RSS
# and each stage's seconds; Draco's encoder on the same PLY files in the same
# run (positions and normals at its defaults), as stipple / Draco; and the fit
# of wall time against n (the exponent of a least-squares line in log-log).
# The median of RUNS runs (default 3) for each row.
#
# usage: tools/bench/encoder_scale.sh [SIZES...]   (default: 1e6 1e7)
#   STIPPLE=build/release/tools/stipple MAKE_SCAN=build/release/tools/stipple-make-scan
#   THREADS=2 RUNS=3 SHARED=../shared/data TMP=/tmp
#   ENCODE_ARGS="--memory 2G"   more encode options (a memory budget: partitions)
set -euo pipefail
cd "$(dirname "$0")/../.."
S=${STIPPLE:-build/release/tools/stipple}
M=${MAKE_SCAN:-build/release/tools/stipple-make-scan}
THREADS=${THREADS:-2} RUNS=${RUNS:-3} SHARED=${SHARED:-../shared/data}
sizes=("$@")
[[ ${#sizes[@]} -gt 0 ]] || sizes=(1e6 1e7)
work=$(mktemp -d "${TMP:-/tmp}/stipple-scale.XXXXXX")
trap 'rm -rf "$work"' EXIT
results=$work/results.jsonl

# One row: the median run of `stipple encode` (by wall time) with /usr/bin/time's
# CPU seconds and peak RSS added, and Draco's median wall time for PLY input.
measure() {
  local name=$1 scan=$2
  local runs=()
  for ((r = 0; r < RUNS; ++r)); do
    /usr/bin/time -f '%U %S %M' -o "$work/time" "$S" encode "$scan" -o "$work/out.spg" --json -q --threads "$THREADS" ${ENCODE_ARGS:-} >"$work/json"
    read -r user sys rss <"$work/time"
    runs+=("$(python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); d["cpu"]=float(sys.argv[2])+float(sys.argv[3]); d["rss_mb"]=int(sys.argv[4])/1024; print(json.dumps(d))' "$work/json" "$user" "$sys" "$rss")")
  done
  local draco=""
  if [[ $scan == *.ply ]] && command -v draco_encoder >/dev/null; then
    local times=()
    for ((r = 0; r < RUNS; ++r)); do
      local t0 t1
      t0=$(date +%s.%N)
      draco_encoder -point_cloud -i "$scan" -o "$work/out.drc" >/dev/null 2>&1 || { times=(); break; }
      t1=$(date +%s.%N)
      times+=("$(python3 -c "print($t1 - $t0)")")
    done
    [[ ${#times[@]} -gt 0 ]] && draco=$(printf '%s\n' "${times[@]}" | sort -g | sed -n "$(((${#times[@]} + 1) / 2))p")
  fi
  printf '%s\n' "${runs[@]}" | python3 -c '
import json, sys
runs = sorted((json.loads(l) for l in sys.stdin), key=lambda d: d["seconds"])
d = runs[len(runs) // 2]
d["name"] = sys.argv[1]
d["draco_seconds"] = float(sys.argv[2]) if sys.argv[2] else None
print(json.dumps(d))' "$name" "$draco" >>"$results"
  echo "  $name done" >&2
}

for n in "${sizes[@]}"; do
  echo "stipple-make-scan: $n points" >&2
  "$M" --points "$n" --normals -o "$work/terrain_$n.ply"
  measure "terrain $n, normals (PLY)" "$work/terrain_$n.ply"
  rm -f "$work/terrain_$n.ply"
  "$M" --points "$n" --colour -o "$work/terrain_$n.las"
  measure "terrain $n, bare, colour (LAS)" "$work/terrain_$n.las"
  rm -f "$work/terrain_$n.las"
done
for scan in "$SHARED"/*.ply; do
  [[ -f $scan ]] && measure "$(basename "$scan")" "$scan"
done

python3 - "$results" "$THREADS" <<'PY'
import json, math, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
for d in rows:  # an older stipple reports no stages
    for k in ("read", "plan", "route", "normals", "hierarchy", "classes", "write"):
        d.setdefault(k + "_seconds", float("nan"))
    d.setdefault("partitions", 1)
print(f"| scan | points | parts | wall s | CPU s | M pt/s wall | M pt/s per CPU-s | peak RSS MB | read | plan | route | normals | hierarchy | classes | write | Draco s | stipple / Draco |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for d in rows:
    n, wall, cpu = d["points"], d["seconds"], d["cpu"]
    draco = d["draco_seconds"]
    print(f"| {d['name']} | {n:,} | {d['partitions']} | {wall:.2f} | {cpu:.2f} | {n / wall / 1e6:.2f} | {n / cpu / 1e6:.2f} | {d['rss_mb']:.0f} | "
          f"{d['read_seconds']:.2f} | {d['plan_seconds']:.2f} | {d['route_seconds']:.2f} | {d['normals_seconds']:.2f} | {d['hierarchy_seconds']:.2f} | {d['classes_seconds']:.2f} | "
          f"{d['write_seconds']:.2f} | {'' if draco is None else f'{draco:.2f}'} | {'' if draco is None else f'{wall / draco:.1f}'} |")
for kind in ("normals (PLY)", "bare, colour (LAS)"):
    pts = [(d["points"], d["seconds"]) for d in rows if d["name"].endswith(kind)]
    if len(pts) >= 2:
        xs = [math.log(p) for p, _ in pts]
        ys = [math.log(t) for _, t in pts]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
        print(f"\nwall time ~ n^{slope:.2f} for the synthetic scans, {kind} ({len(pts)} sizes, {sys.argv[2]} threads)")
PY
