#!/usr/bin/env bash
# The vision demo (`./run demo vision`): replays the bundled hard-conditions
# footage of datasets/ through the whole pipeline, prints the summary and the score
# against ground truth, and writes the annotated video and the tracks to out/demo/.
set -euo pipefail
RILBED="$1"; shift || true
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
OUT="${RILBED_DEMO_OUT:-$ROOT/out/demo}"
CLIP="${RILBED_DEMO_CLIP:-$ROOT/datasets/hard}"
mkdir -p "$OUT"
echo "== rilbed demo: $(basename "$CLIP") footage, 8 robots with 6UCP markers =="
"$RILBED" detect "$CLIP/frames" --calib "$CLIP/calibration.yaml" \
  --csv "$OUT/tracks.csv" --annotate "$OUT/annotated.avi" "$@"
echo "== against ground truth =="
"$RILBED" score --truth "$CLIP/ground_truth.csv" --detections "$OUT/tracks.csv"
echo "== wrote =="
echo "  tracks:          $OUT/tracks.csv ($(($(wc -l < "$OUT/tracks.csv") - 1)) rows)"
echo "  annotated video: $OUT/annotated.avi"
