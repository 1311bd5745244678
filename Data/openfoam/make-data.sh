#!/usr/bin/env bash
# Regenerates Data/windAroundBuildings and Data/flange from Debian 12's packages (openfoam,
# openfoam-examples, scotch, paraview): OpenFOAM tutorial -> mesh + solve -> Scotch graph
# partition -> .vtu pieces -> read back and checked. See Data/README.md.
#
#   bash Data/openfoam/make-data.sh        (scratch: $APC_DATA_WORK or a mktemp dir)
#
# Every tutorial step runs by hand: Debian's OpenFOAM has no bin/tools/RunFunctions, so the
# tutorials' Allrun scripts do not work.
#
# Partitioning route: Debian's decomposePar links dummy stubs for "method scotch"/"metis", so
# scotch_partition.py builds the cell graph from owner/neighbour, partitions it with Debian's
# real `scotch_gpart` (deterministic mode) and decomposePar applies it with `method manual`.
# APC_PARTITIONER=apc uses APC's own filter instead (apc_partition.py: vtkAPCGraphPartition,
# METIS on the dual graph of the OpenFOAM cells, through pvpython and the APC plugin, which
# must be built first). The bundled data were made with the default, scotch.
set -euo pipefail
export LC_ALL=C  # printf/awk decimal points
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
here=$repo/Data/openfoam
bash "$repo/.ci/install-deps" data

work=${APC_DATA_WORK:-$(mktemp -d /tmp/apc-data.XXXXXX)}
mkdir -p "$work"
tutorials=/usr/share/doc/openfoam-examples/examples
export WM_PROJECT=OpenFOAM WM_PROJECT_VERSION=v1912
WM_PROJECT_DIR=$(dpkg -L openfoam | grep '/share/openfoam$')
export WM_PROJECT_DIR
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
python=/usr/bin/python3  # Debian's, with python3-numpy (not a pyenv/venv python from PATH)
pvpython() { xvfb-run -a /usr/bin/pvpython --force-offscreen-rendering "$@"; }  # GLX-only build
: > "$work/timings.txt"

# step NAME CMD...: run CMD in the current case, log to log.NAME, print the wall time.
step() {
  local name=$1 t0 t1
  shift
  t0=$(date +%s.%N)
  if ! "$@" > "log.$name" 2>&1; then
    tail -n 30 "log.$name"
    echo "make-data: step $name failed in $PWD (log: $PWD/log.$name)" >&2
    exit 1
  fi
  t1=$(date +%s.%N)
  printf '%-34s %7.1f s\n' "$(basename "$PWD"): $name" "$(awk "BEGIN { print $t1 - $t0 }")" | tee -a "$work/timings.txt"
}

# manual_decomposition N: graph partition into N parts (Scotch, or APC's filter with
# APC_PARTITIONER=apc), and a decomposeParDict that uses it.
manual_decomposition() {
  if [ "${APC_PARTITIONER:-scotch}" = apc ]; then
    PYTHONPATH="$repo/Plugin/Python" pvpython "$here/apc_partition.py" . "$1" "cellDecomposition$1"
  else
    "$python" "$here/scotch_partition.py" . "$1" "cellDecomposition$1"
  fi
  cat > system/decomposeParDict << EOF
FoamFile { version 2.0; format ascii; class dictionary; object decomposeParDict; }
numberOfSubdomains $1;
method manual;
coeffs { dataFile "cellDecomposition$1"; }
EOF
}

# Fresh copy of a tutorial; Debian gzips its files (OpenFOAM reads the .obj.gz surface itself).
copy_tutorial() {
  rm -rf "${work:?}/$2"
  cp -r "$tutorials/$1" "$work/$2"
  find "$work/$2" -name '*.gz' ! -path '*/triSurface/*' -exec gunzip {} +
  cd "$work/$2"
}

# --- windAroundBuildings: 185k cells (hex, prism, polyhedra), fields p, U (k, epsilon) -----
copy_tutorial incompressible/simpleFoam/windAroundBuildings wind
# 200 iterations, one write at the end; no function objects (ensight/vtk writers and the
# runTimePostProcessing renderer: slow and not needed).
foamDictionary -entry functions -remove system/controlDict > /dev/null
foamDictionary -entry endTime -set 200 system/controlDict > /dev/null
foamDictionary -entry writeInterval -set 200 system/controlDict > /dev/null
step surfaceFeatureExtract surfaceFeatureExtract
step blockMesh blockMesh
step snappyHexMesh snappyHexMesh -overwrite
cp -r 0.orig 0
step scotch2 manual_decomposition 2
tail -n 1 log.scotch2
step decomposePar2 decomposePar -force
step simpleFoam-np2 mpirun -np 2 --oversubscribe simpleFoam -parallel
step reconstructPar reconstructPar -latestTime
step scotch8 manual_decomposition 8
tail -n 1 log.scotch8
# -cellDist also writes the processor id of every cell as a field: the exporter cuts by it.
step decomposePar8 decomposePar -force -latestTime -cellDist
rm -f "$repo"/Data/windAroundBuildings/wind*.vtu "$repo"/Data/windAroundBuildings/wind.pvtu
step export-vtu pvpython "$here/export_vtu.py" . "$repo/Data/windAroundBuildings" wind p U --pieces

# --- flange: 5.7k cells (hex, prism), field T -----------------------------------------------
copy_tutorial basic/laplacianFoam/flange flange
step ansysToFoam ansysToFoam flange.ans -scale 0.001
step laplacianFoam laplacianFoam
step scotch4 manual_decomposition 4
tail -n 1 log.scotch4
step decomposePar4 decomposePar -force -latestTime -cellDist
rm -f "$repo"/Data/flange/flange*.vtu "$repo"/Data/flange/flange.pvtu
step export-vtu pvpython "$here/export_vtu.py" . "$repo/Data/flange" flange T --whole --pieces

# --- read everything back --------------------------------------------------------------------
cd "$work"
data=$repo/Data
step verify pvpython "$here/verify_vtu.py" "$data/flange/flange.vtu" "$data/flange/flange.pvtu" \
  "$data/windAroundBuildings/wind.pvtu"
cat log.verify

echo "--- timings (also in $work/timings.txt)"
cat "$work/timings.txt"
echo "--- sizes"
(cd "$data" && du -b flange/* windAroundBuildings/* && du -sh .)
[ -n "${APC_DATA_WORK:-}" ] || rm -rf "$work"
