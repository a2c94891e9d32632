#!/usr/bin/env bash
# The main demo (`./run demo`): convoy_sim in real time. Eight virtual Kheperas start at
# random poses in the lab's 1.5 x 1.2 m field and form a convoy; rilbed prints every
# robot's behaviour once a second, ends 5 s after the convoy formed (or on Ctrl-C), and
# writes the run folder to out/demo/convoy_sim.
#   tools/demo.sh RILBED [vision | extra `rilbed run` options...]
# `vision` runs the overhead-camera demo instead (tools/demo_vision.sh).
set -euo pipefail
RILBED="$1"; shift || true
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
if [[ "${1:-}" == vision ]]; then
  shift
  exec "$ROOT/tools/demo_vision.sh" "$RILBED" "$@"
fi
OUT="${RILBED_DEMO_OUT:-$ROOT/out/demo}/convoy_sim"
rm -rf "$OUT"
echo "== rilbed demo: convoy_sim in real time (8 virtual Kheperas; Ctrl-C ends it) =="
"$RILBED" run "$ROOT/scenarios/convoy_sim.yaml" --realtime --stop-when-formed --seed "${RILBED_DEMO_SEED:-1}" \
  --out "$OUT" "$@"
echo "== wrote $OUT: trajectories.csv, events.csv, summary.json, trajectories.svg =="
