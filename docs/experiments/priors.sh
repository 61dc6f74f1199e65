#!/bin/bash
# The prior experiment of docs/book/src/fit.md on the real dVRK data (../shared/data/dvrk): the prior is
# the fit of one whole trajectory (SDP, delays, Stribeck); the fit is periods 2-3 of the
# other; the test is that one's first period. Prints the mean test relative error per
# prior metric and weight. Needs the release binary (cargo build --release).
set -e
cd "$(dirname "$0")/../.." && ROOT=$PWD
B=${DVRK_IDENT_BIN:-$ROOT/target/release/dvrk-ident}; D=${SHARED:-$ROOT/../shared}/data/dvrk
OUT=$(mktemp -d); cd "$OUT"
for arm in psm mtm; do
  if [ $arm = psm ]; then C=16.965; W=1111; else C=5.655; W=2000; fi
  P="--robot $arm --format wpi-csv --rate 200 --cutoff $C --filter-torque --trim 200 --stribeck 0.3 --delay auto"
  $B fit $D/$arm/one_results.csv $P --out $arm-one.json > /dev/null
  $B fit $D/$arm/two_results.csv $P --out $arm-two.json > /dev/null
  for dir in "one two" "two one"; do
    set -- $dir; pr=$1; tr=$2
    sed -n "$((W+1)),$((3*W))p" $D/$arm/${tr}_results.csv > short-$arm-$tr.csv
    for spec in "none" "entropic 1e-3" "entropic 1e-2" "entropic 1e-1" "entropic 1" "entropic 10" "euclidean 1e-3" "euclidean 1e-2" "euclidean 1e-1" "euclidean 1" "euclidean 10"; do
      set -- $spec
      if [ $1 = none ]; then X=""; else X="--prior $arm-$pr.json --prior-metric $1 --prior-weight $2"; fi
      echo -n "$arm prior $pr, short $tr, $spec: "
      $B fit short-$arm-$tr.csv $P $X --test $D/$arm/${tr}_results.csv --test-window $W --json 2>/dev/null | python3 -c 'import json,sys
r=json.load(sys.stdin); m=r["metrics"]["test"]["relative_error"]
print(r["solver"]["status"], r["physically_consistent"], "%.4f"%(sum(m)/len(m)), " ".join("%.4f"%x for x in m), r.get("prior_divergence"))' || echo FAIL
    done
  done
done
