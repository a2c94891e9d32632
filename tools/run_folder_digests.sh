#!/usr/bin/env bash
# Digests of the shipped scenarios' run folders, to show that a change of the code left
# what runs write as it was: convoy_sim, wander, beacon, track_following and
# `convoy_mixed --all-virtual`, seeds 1-5, each file's SHA-256. summary.json is digested
# without its wall-clock fields (wall_s, run_wall_s), the only bytes that differ from one
# run of the same seed to the next.
#
#   tools/run_folder_digests.sh RILBED_BINARY [WORK_DIR]  > digests.txt
#   diff before.txt after.txt   # no output: byte for byte the same run folders
set -euo pipefail
bin="${1:?usage: run_folder_digests.sh RILBED_BINARY [WORK_DIR]}"
root="$(cd "$(dirname "$0")/.." && pwd)"
work="${2:-$(mktemp -d)}"
mkdir -p "$work"
seeds=(1 2 3 4 5)
runs=(
  "convoy_sim|scenarios/convoy_sim.yaml|"
  "wander|scenarios/wander.yaml|"
  "beacon|scenarios/beacon.yaml|"
  "track_following|scenarios/track_following.yaml|"
  "convoy_mixed_all_virtual|scenarios/convoy_mixed.yaml|--all-virtual"
)
for entry in "${runs[@]}"; do
  IFS='|' read -r name file extra <<< "$entry"
  for seed in "${seeds[@]}"; do
    out="$work/$name/seed_$seed"
    rm -rf "$out"
    # shellcheck disable=SC2086 # $extra is zero or one flag
    "$bin" run "$root/$file" --seed "$seed" --out "$out" --quiet $extra > /dev/null
    for f in "$out"/*; do
      base="$(basename "$f")"
      if [[ $base == summary.json ]]; then
        digest="$(grep -v -E '"(run_)?wall_s"' "$f" | sha256sum | cut -d' ' -f1)"
      else
        digest="$(sha256sum "$f" | cut -d' ' -f1)"
      fi
      printf '%s  %s/seed_%s/%s\n' "$digest" "$name" "$seed" "$base"
    done
  done
done
