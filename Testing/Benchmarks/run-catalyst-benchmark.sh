#!/usr/bin/env bash
# In situ: APC Volume against ParaView's own Volume in the same Catalyst pipeline. The
# Catalyst example (Examples/Catalyst: apcCatalystMiniApp, a tracer carried by the wind on the
# bundled 331,699-cell mesh in 8 Scotch pieces, each rank advancing its own pieces) runs with
# the example's script once per representation and rank count ($APC_INSITU_RANKS, default
# "1 2 4"), the same steps each time ($APC_INSITU_STEPS steps, Catalyst output every
# $APC_INSITU_EVERY: steps 0, every, 2 every, ...; the field changes between them, so every
# output step is a new data set for the renderer). Per processed step: the Catalyst call's wall
# time (slowest rank: render and write the PNG); per rank: peak resident memory of the whole
# process (simulation, Python, ParaView). APC and ParaView alternate per rank count, so both
# see the same machine load. Writes $APC_INSITU_OUT (default docs/evaluation/catalyst):
# steps.csv (the mini-app's lines), summary.csv (per rank count: mean step time after the
# first, ratio APC / ParaView, first step, peak memory), the last step's PNGs and the logs.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
out=${APC_INSITU_OUT:-$top/docs/evaluation/catalyst}
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
steps=${APC_INSITU_STEPS:-300}
every=${APC_INSITU_EVERY:-100}
size=${APC_INSITU_SIZE:-640 400}
csv="$out/steps.csv"
rm -f "$csv"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for n in ${APC_INSITU_RANKS:-1 2 4}; do
  for rep in "APC Volume" "Volume"; do
    tag=$( [ "$rep" = Volume ] && echo paraview || echo apc )
    echo "== $rep, $n rank(s); load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
    # shellcheck disable=SC2086
    bash "$top/.ci/with-xvfb" mpirun --oversubscribe -np "$n" \
      "$top/build/bin/apcCatalystMiniApp" \
      --script "$top/Examples/Catalyst/apc_catalyst_tracer.py" --steps "$steps" --every "$every" \
      --size $size --representation "$rep" --output "$work/${tag}_np$n" --csv "$csv" \
      >"$work/${tag}_np$n.log" 2>&1 || true
    # The mini-app's own lines (ParaView's log lines stay in the work folder).
    grep -E "^step|peak memory|apcCatalystMiniApp|APC stages" "$work/${tag}_np$n.log" \
      >"$out/${tag}_np$n.log" || true
    cat "$out/${tag}_np$n.log"
    cp "$(ls "$work/${tag}_np$n"/tracer_*.png | tail -n 1)" "$out/${tag}_np$n.png"
  done
done
python3 "$top/Examples/Catalyst/compare_runs.py" "$csv" --summary "$out/summary.csv"
cat "$out/summary.csv"
