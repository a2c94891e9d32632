#!/usr/bin/env bash
# CTest `lcmtypes_java` (label e2e): the Java types of build/rilbed_lcmtypes.jar, the ones
# lcm-spy uses, read every message of real rilbed runs. Three short runs (a convoy on the
# in-process bus, obstacles and beacons, a track) are recorded with --record; DecodeRilbedLog
# decodes each log by fingerprint, as lcm-spy does, and checks it against the run folder the
# same run wrote. A log checked against another run's folder must fail (the checks bite).
#
#   lcmtypes_java_test.sh JAVA CLASSPATH RILBED SOURCE_DIR TYPE...
set -euo pipefail
JAVA="$1" CP="$2" RILBED="$3" SRC="$4"
shift 4
TYPES=("$@")
WORK="$(mktemp -d "${TMPDIR:-/tmp}/rilbed_lcmtypes_java.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"

failed=0
fail() {
  printf 'FAIL: %s\n' "$*"
  failed=1
}

# decode NAME: DecodeRilbedLog on NAME.lcm against the folder NAME/, its output in NAME.txt.
decode() {
  if ! "$JAVA" -cp "$CP" DecodeRilbedLog "$1.lcm" "$1" "${TYPES[@]}" > "$1.txt" 2>&1; then
    fail "$1: DecodeRilbedLog failed"
  fi
  sed "s/^/  $1: /" "$1.txt"
}

# expect NAME LINE: NAME.txt holds LINE exactly.
expect() {
  grep -qxF -- "$2" "$1.txt" || fail "$1: no line '$2'"
}

run() {
  local name="$1"
  shift
  "$RILBED" run "$@" --record "$name.lcm" --out "$name" --quiet > "$name.run.txt" 2>&1 ||
    { cat "$name.run.txt"; fail "$name: rilbed run failed"; }
}

run convoy "$SRC/scenarios/convoy_sim.yaml" --stop-when-formed --seed 3 --lcm memq://
run beacon "$SRC/scenarios/beacon.yaml" --duration 5
run track "$SRC/scenarios/track_following.yaml" --duration 5

for name in convoy beacon track; do
  decode "$name"
  grep -q '^ok: ' "$name.txt" || fail "$name: not ok"
  for c in 'RILBED_WORLD rilbed.world_t' 'RILBED_POSES rilbed.poses_t' 'RILBED_STATUS rilbed.status_t'; do
    grep -q "^$c [1-9]" "$name.txt" || fail "$name: no $c"
  done
  expect "$name" "RILBED_SUMMARY rilbed.summary_t 1"
done
# What each world holds, as the scenario files say.
expect convoy "world convoy_sim 1.50x1.20 walls=true robots=8 obstacles=0 tracks=0 beacons=0"
grep -q '^RILBED_EVENTS rilbed.event_t [1-9]' convoy.txt || fail "convoy: no events"
grep -q '^status convoy_sim seed=3 ended_by=formed formed=true ' convoy.txt || fail "convoy: not formed"
expect beacon "world beacon 1.50x1.20 walls=true robots=4 obstacles=1 [0.70,0.45 0.78,0.45 0.78,0.75 0.70,0.75 closed w=0.000] tracks=0 beacons=2 (0.05,1.15) (1.45,0.60)"
grep -q '^status beacon seed=1 ended_by=duration ' beacon.txt || fail "beacon: not ended by its duration"
grep -q '^world track_following 1.50x1.20 .* robots=2 obstacles=0 tracks=1 \[0.30,0.30 1.20,0.30 1.30,0.60 1.20,0.90 0.30,0.90 0.20,0.60 .*w=0.025\] beacons=0$' track.txt ||
  fail "track: not the scenario's loop of tape"

# The checks bite: the convoy's log against the beacon run's folder fails.
if "$JAVA" -cp "$CP" DecodeRilbedLog convoy.lcm beacon "${TYPES[@]}" > mismatch.txt 2>&1; then
  fail "the convoy's log passed against the beacon run's folder"
fi
grep -q '^FAIL: trajectories.csv row 1 ' mismatch.txt || fail "the mismatch was not found in trajectories.csv"

if ((failed)); then
  echo "lcmtypes_java: FAILED"
  exit 1
fi
echo "lcmtypes_java: ok"
