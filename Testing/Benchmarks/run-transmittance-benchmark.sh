#!/usr/bin/env bash
# Pass 2's transmittance query (apcTransmittanceBenchmark at 4, 6 and 8 moments): ns per query
# and per pixel set-up, into out/benchmark/transmittance.csv. Arguments go to the program:
# [pixels] [repeats] [4|6|8].
# Before/after in one run: APC_BASELINE_BUILD=<another build dir> (e.g. a `git worktree` of
# main built with .ci/build's settings) runs that build's apcTransmittanceBenchmark too,
# alternating with this one for APC_BENCH_ROUNDS rounds (3), into transmittance_baseline.csv,
# and prints baseline/this ratios of the best rounds and whether both answer alike.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
out="${APC_BENCH_OUT:-$top/out/benchmark}"
mkdir -p "$out"
this="$out/transmittance.csv"
base="$out/transmittance_baseline.csv"
rm -f "$this" "$base"
for round in $(seq "${APC_BENCH_ROUNDS:-3}"); do
  # Alternating rounds: the machine's frequency changes and neighbours hit both builds alike.
  if [ -n "${APC_BASELINE_BUILD:-}" ]; then
    "$APC_BASELINE_BUILD/bin/apcTransmittanceBenchmark" "$@" >>"$base"
  fi
  "$top/build/bin/apcTransmittanceBenchmark" "$@" >>"$this"
done
cat "$this"
[ -n "${APC_BASELINE_BUILD:-}" ] || exit 0

/usr/bin/python3 - "$base" "$this" <<'PY'
import csv
import sys


def best(path):
    """Per number of moments: the fastest round's ns per query and the answers' mean T."""
    rows = [r for r in csv.DictReader(open(path)) if r["moments"] != "moments"]
    out = {}
    for r in rows:
        # Builds from before this program dropped its frozen old copy print the current
        # implementation as new_ns_per_query.
        ns = float(r.get("ns_per_query") or r["new_ns_per_query"])
        build = float(r.get("ns_per_build") or r["new_ns_per_build"])
        old = out.get(r["moments"])
        if old is None or ns < old[0]:
            out[r["moments"]] = (ns, build, r.get("mean_T", "?"))
    return out


base, this = best(sys.argv[1]), best(sys.argv[2])
print("moments,baseline_ns_per_query,ns_per_query,baseline/this,baseline_ns_per_build,"
      "ns_per_build,same_answers")
for m in sorted(this, key=int):
    if m in base:
        b, t = base[m], this[m]
        print("%s,%.2f,%.2f,%.2f,%.1f,%.1f,%s" % (m, b[0], t[0], b[0] / t[0], b[1], t[1],
                                                 "yes" if b[2] == t[2] else "no or unknown"))
PY
