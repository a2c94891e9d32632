#!/usr/bin/env bash
# The main demo (`./run demo`): convoy_mixed in real time, as in paper 001 Fig. 5. Six
# virtual Kheperas and two real ones (emulated Kheperas on pseudo-terminals, driven over
# the real serial link and seen by an emulated overhead camera through the real detector)
# start at random poses in the lab's 1.5 x 1.2 m field and form one convoy. It serves the
# web panel (its address is printed; opened in a browser when there is a display), prints
# every robot's behaviour once a second, runs the scenario's duration (Exit on the panel or
# Ctrl-C ends it sooner), stops the real robots, and writes the run folder to
# out/demo/convoy_mixed.
#   tools/demo.sh RILBED [sim | vision | extra `rilbed run` options...]
# `sim` runs convoy_sim (all virtual); `vision` the camera demo (tools/demo_vision.sh).
set -euo pipefail
RILBED="$1"; shift || true
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
if [[ "${1:-}" == vision ]]; then
  shift
  exec "$ROOT/tools/demo_vision.sh" "$RILBED" "$@"
fi
SCENARIO=convoy_mixed
WHAT="6 virtual and 2 real (emulated) Kheperas"
if [[ "${1:-}" == sim ]]; then
  shift
  SCENARIO=convoy_sim
  WHAT="8 virtual Kheperas"
fi
OUT="${RILBED_DEMO_OUT:-$ROOT/out/demo}/$SCENARIO"
rm -rf "$OUT"
echo "== rilbed demo: $SCENARIO in real time ($WHAT; Exit on the panel or Ctrl-C ends it) =="
# The panel's address is the run's first line; open it when a browser can show it.
open_panel() {
  trap '' INT TERM  # Ctrl-C is rilbed's to handle (it stops the robots); read to its end
  while IFS= read -r line; do
    printf '%s\n' "$line"
    if [[ "$line" == "rilbed gui: http"* && -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ]] && command -v xdg-open > /dev/null; then
      xdg-open "${line#rilbed gui: }" > /dev/null 2>&1 || true
    fi
  done
}
"$RILBED" run "$ROOT/scenarios/$SCENARIO.yaml" --realtime --seed "${RILBED_DEMO_SEED:-1}" \
  --gui --gui-port "${RILBED_GUI_PORT:-8080}" --out "$OUT" "$@" | open_panel
echo "== wrote $OUT: trajectories.csv, events.csv, summary.json, trajectories.svg =="
