#!/usr/bin/env bash
# Runs rilbed's benchmarks and prints their tables (Markdown) on stdout.
#   tools/bench.sh [BUILD_DIR] [bench_vision options...]
# `./run bench` calls it with its Release build directory. On its own it uses
# BUILD_DIR (default: build/ next to this tools/ folder) and builds the bench_vision
# target there first if it is missing, configuring a Release build if the directory
# has none. Options after BUILD_DIR go to bench_vision (--quick, --budget S, ...).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD_DIR="${1:-$ROOT/build}"
shift || true

if [[ ! -x "$BUILD_DIR/bench_vision" ]]; then
  echo "[bench] $BUILD_DIR/bench_vision not built yet; building it (one job)" >&2
  if [[ ! -f "$BUILD_DIR/CMakeCache.txt" ]]; then
    cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release >&2
  fi
  cmake --build "$BUILD_DIR" -j1 --target bench_vision >&2
fi

BUILD_TYPE="$(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$BUILD_DIR/CMakeCache.txt" 2>/dev/null || true)"
if [[ "$BUILD_TYPE" != Release ]]; then
  echo "[bench] warning: $BUILD_DIR is a '${BUILD_TYPE:-unknown}' build; timings mean little outside Release" >&2
fi
export RILBED_BENCH_BUILD_TYPE="${BUILD_TYPE:-unknown}"
RILBED_BENCH_APRILTAG_VERSION="$(pkg-config --modversion apriltag 2>/dev/null || echo 3)"
export RILBED_BENCH_APRILTAG_VERSION
# Which sources were measured: the commit, and any uncommitted change under src/.
if SOURCE="$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null)"; then
  DIRTY="$(git -C "$ROOT" status --porcelain -- src 2>/dev/null | awk '{print $2}' | tr '\n' ' ')"
  [[ -n "$DIRTY" ]] && SOURCE="$SOURCE, uncommitted changes in: ${DIRTY% }"
  export RILBED_BENCH_SOURCE="$SOURCE"
fi

# The vision comparisons time every detector with glibc's malloc thresholds fixed: glibc
# moves its mmap threshold as a program runs and may map a frame's large buffers afresh every
# frame, and page faults cost a peer several times its time on identical frames.
export GLIBC_TUNABLES=glibc.malloc.mmap_threshold=67108864:glibc.malloc.trim_threshold=268435456
"$BUILD_DIR/bench_vision" "$@"

# The vision stress set: 500 random scenes (2,000 frames) from a fresh seed,
# full-frame and tracked, and the search's cost on plain and textured floors beside
# AprilTag and ArUco. Its seed is printed; pass it back to see the same frames.
echo
"$BUILD_DIR/bench_stress" --scenes 500
# The second generator's lab footage, which no threshold was tuned on (light traced from
# the lamp through a lens onto robots' tops and paper stickers, rolling shutter, shot
# noise, JPEG): 60 scenes (240 frames) from a fresh seed, its targets, and the full and
# tracked search's cost on its frames beside AprilTag and ArUco.
echo
"$BUILD_DIR/bench_stress" --generator lab --scenes 60
unset GLIBC_TUNABLES

# The simulation: sim-bench's table, then the convoy batch in both modes
# (wall time of the whole command, as a user sees it).
echo
"$BUILD_DIR/rilbed" sim-bench --robots 100,1000,10000 --seconds 10
# Python controllers beside the C++ one (same world, same seed), then one call's cost.
echo
GLIBC_TUNABLES=glibc.malloc.mmap_threshold=67108864:glibc.malloc.trim_threshold=268435456 "$BUILD_DIR/bench_python" --swarm-seconds 5
echo
echo "## Convoy batch: 100 seeds of scenarios/convoy_sim.yaml, --fast --stop-when-formed"
echo
echo "Each row is one \`rilbed run --seeds 100\` with its wall time (all cores, one run per core)."
for mode in distributed central; do
  start=$(date +%s.%N)
  "$BUILD_DIR/rilbed" run "$ROOT/scenarios/convoy_sim.yaml" --fast --stop-when-formed --seeds 100 --quiet --mode "$mode" \
    | { if [[ $mode == distributed ]]; then tail -3; else tail -1; fi; }
  end=$(date +%s.%N)
  echo "  (whole command: $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') s)"
done

# Agents in other processes: time per lock-step quantum over the paper's grid,
# on loopback multicast inside a private network namespace (nothing leaves the machine),
# then again with 10 % of the packets dropped by nftables (quanta on 7667, answers on 7668).
echo
if unshare -n true 2>/dev/null; then
  URL='udpm://239.255.76.67:7667?ttl=0'
  NS_SETUP='ip link set lo up; ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo'
  unshare -n bash -c "$NS_SETUP; '$BUILD_DIR/rilbed' quantum-bench --table --quanta 1000 --lcm '$URL'"
  if unshare -n nft add table inet probe 2>/dev/null; then
    echo
    unshare -n bash -c "$NS_SETUP
      nft add table inet loss
      nft add chain inet loss in '{ type filter hook input priority 0; policy accept; }'
      nft add rule inet loss in udp dport '{ 7667, 7668 }' numgen random mod 10 0 drop
      '$BUILD_DIR/rilbed' quantum-bench --robots 40 --processes 12 --quanta 1000 --lcm '$URL' \
        --condition '10 % of the packets to ports 7667 (quanta) and 7668 (answers) dropped at random (nftables)'
      '$BUILD_DIR/rilbed' quantum-bench --robots 1000 --processes 8 --quanta 200 --lcm '$URL' \
        --condition '10 % of the packets to ports 7667 (quanta) and 7668 (answers) dropped at random (nftables)' | grep '^| 1000 '"
  fi
else
  echo "(quantum-bench skipped: no network namespace here, unshare -n needs root)"
fi

# Robot in the loop: frame arrival to the D command on each real (emulated) robot's port.
echo
"$BUILD_DIR/rilbed" loop-bench --real 8 --virtual 100 --frames 300

# track_explore on random tape networks (layouts drawn after its last change), five and
# three track elements, then under wheel slip the odometer does not count.
echo
"$BUILD_DIR/bench_track_explore" --kinds grid,tree,loop --layouts 301-303 --starts 20 --start-seed 13
"$BUILD_DIR/bench_track_explore" --kinds grid,tree,loop --layouts 301-303 --starts 20 --start-seed 13 --elements 3 --spacing-mm 15
"$BUILD_DIR/bench_track_explore" --kinds grid,tree,loop --layouts 301-303 --starts 20 --start-seed 13 --slip 0.02
# Paper 000's tape-width experiment (tools/plot_tape_width.py plots the CSV).
"$BUILD_DIR/bench_track_explore" --kinds grid,tree,loop --layouts 301-303 --starts 10 --start-seed 13 \
  --tape-mm 5,10,15,20,25,30 --csv "$BUILD_DIR/tape_width.csv"

# The web panel: viewers of a 100-robot run (frames and bytes each gets, their effect on the
# run's loop latency), then the page's drawing rate in headless Chromium.
echo
"$BUILD_DIR/bench_gui" --robots 100 --seconds 10 --repeat 3
