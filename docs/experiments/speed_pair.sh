#!/bin/bash
# The speed pair of docs/book/src/generalization.md (issue 28) on ../shared/data/dvrk/psm_speed:
# fit one speed, test on the other (whole test log), 2019 processing, with the half-speed
# log at its real 100 Hz clock (converted to a headered CSV with time stamps). Prints the
# mean test relative error and the per-joint errors of each row. Needs the release binary.
set -e
cd "$(dirname "$0")/../.." && ROOT=$PWD
B=${DVRK_IDENT_BIN:-$ROOT/target/release/dvrk-ident}; D=${SHARED:-$ROOT/../shared}/data/dvrk/psm_speed
OUT=$(mktemp -d); cd "$OUT"
$B convert $D/one_speed_1.0_105g.csv full.csv --in-format wpi --rate 200 > /dev/null
$B convert $D/one_speed_0.5_105g.csv half.csv --in-format wpi --rate 100 > /dev/null
show='import json,sys
r=json.load(sys.stdin); m=r["metrics"]["test"]["relative_error"]
print("mean %.3f |"%(sum(m)/len(m)), " ".join("%.3f"%x for x in m))'
row() { # label, then fit flags
  label=$1; shift
  for dir in "full half" "half full"; do
    set -- $dir "${@:3}"; a=$1; b=$2
    echo -n "$label, $a -> $b: "
    $B fit $a.csv --robot ${ROBOT:-psm} ${P:---cutoff 16.965 --filter-torque} "${@:3}" --test $b.csv --json 2>/dev/null | python3 -c "$show" || echo FAIL
  done
}
ROWS=(
  "WLS|--method wls"
  "SDP|--method sdp"
  "SDP, Stribeck 0.3|--method sdp --stribeck 0.3"
  "SDP, delays|--method sdp --delay auto"
  "SDP, delays, Stribeck 0.3 (the preset before Dahl)|--method sdp --delay auto --stribeck 0.3"
  "SDP, delays, Stribeck 0.1|--method sdp --delay auto --stribeck 0.1"
  "SDP, delays, Stribeck 0.2|--method sdp --delay auto --stribeck 0.2"
  "SDP, delays, Stribeck 0.5|--method sdp --delay auto --stribeck 0.5"
  "SDP, delays, Stribeck 1.0|--method sdp --delay auto --stribeck 1.0"
  "SDP, Stribeck 0.3, the full-speed log's delays|--method sdp --stribeck 0.3 --delay 0.00054,0,0.0061,0.0174,0.0915,0.0725,0.0582"
  "SDP, Stribeck 0.3, the half-speed log's delays|--method sdp --stribeck 0.3 --delay 0.00066,0.00029,0.0071,0.025,0.15,0.146,0.125"
  "WLS, Dahl 20|--method wls --dahl 20"
  "SDP, Dahl 20|--method sdp --dahl 20"
  "SDP, Stribeck 0.3, Dahl 20 (--preset dvrk)|--preset dvrk"
  "SDP, Stribeck 0.3, Dahl 10|--method sdp --stribeck 0.3 --dahl 10"
  "SDP, Stribeck 0.3, Dahl 50|--method sdp --stribeck 0.3 --dahl 50"
  "SDP, delays, Stribeck 0.3, Dahl 20|--method sdp --delay auto --stribeck 0.3 --dahl 20"
  "--preset dvrk, position torque 1|--preset dvrk --position-torque 1"
  "--preset dvrk, position torque 2|--preset dvrk --position-torque 2"
  "--preset dvrk, load friction|--preset dvrk --load-friction"
  "--preset dvrk, load friction, position torque 1|--preset dvrk --load-friction --position-torque 1"
  "SDP, load friction|--method sdp --load-friction"
  "WLS, load friction|--method wls --load-friction"
)
for r in "${ROWS[@]}"; do
  IFS='|' read -r label flags <<< "$r"
  # shellcheck disable=SC2086
  row "$label" x x $flags
done
for p in "--cutoff 16.965" "--cutoff 8.48 --filter-torque" "--cutoff 30 --filter-torque"; do
  P="$p" row "--preset dvrk, $p" x x --preset dvrk
done
# The monotone friction element on every friction frame of the PSM.
sed "s/^friction = true$/friction = true\nmonotone_friction = { velocities = [0.05, 0.2] }/" \
  "$ROOT/robots/psm.toml" > psm_mono.toml
ROBOT=psm_mono.toml row "SDP, delays, monotone_friction 0.05 0.2" x x --method sdp --delay auto
for t in full half; do
  echo -n "both speeds, --preset dvrk --resample 200, test $t: "
  $B fit full.csv half.csv --robot psm --cutoff 16.965 --filter-torque --preset dvrk --resample 200 --test $t.csv --json 2>/dev/null | python3 -c "$show" || echo FAIL
done
# The position torque on q1, q2 and the load friction on q1-q3 (or q2) only, from a description.
python3 - "$ROOT/robots/psm.toml" <<'PY'
import sys
parts = open(sys.argv[1]).read().split("[[frames]]")
def variant(name, adds):
    p = list(parts)
    for frame, line in adds:  # parts[0] is the header, whose comment names [[frames]]
        p[frame + 1] = p[frame + 1].replace("friction = true\n", "friction = true\n" + line + "\n", 1)
    open(name, "w").write("[[frames]]".join(p))
variant("psm_pt1.toml", [(1, "position_torque = { order = 1 }"), (2, "position_torque = { order = 1 }")])
variant("psm_pt2.toml", [(1, "position_torque = { order = 2 }"), (2, "position_torque = { order = 2 }")])
variant("psm_load123.toml", [(f, "load_friction = true") for f in (1, 2, 8)])
variant("psm_load2.toml", [(2, "load_friction = true")])
PY
for d in pt1 pt2 load123 load2; do
  ROBOT=psm_$d.toml row "--preset dvrk, psm_$d.toml" x x --preset dvrk
done
