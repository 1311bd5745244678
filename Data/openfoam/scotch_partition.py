#!/usr/bin/env python3
"""Partition an OpenFOAM mesh's cell graph with Scotch and write the cell->part list for
decomposePar's `method manual`.

Why by hand: Debian's OpenFOAM links decomposePar against dummy stubs of its scotch/metis
decomposition libraries ("method scotch" fails), but Debian's package `scotch` ships the real
`scotch_gpart`. So: cell graph from constant/polyMesh/{owner,neighbour} (one edge per internal
face) -> Scotch source graph (.grf) -> scotch_gpart -> labelList constant/<name>.

usage: scotch_partition.py CASE NPARTS NAME   (writes CASE/constant/NAME)
"""
import re
import subprocess
import sys
import tempfile

import numpy as np

from foam_label_list import write_label_list


def read_label_list(path):
    """An OpenFOAM labelList file, ascii or binary (label=32, as Debian builds it)."""
    data = open(path, "rb").read()
    header = data[: data.index(b"}") + 1].decode()
    body = data[data.index(b"}") + 1 :]
    body = re.sub(rb"//[^\n]*", b"", body, count=1)  # the '// * * *' line after the header
    m = re.search(rb"(\d+)\s*\(", body)
    n, start = int(m.group(1)), m.end()
    if re.search(r"format\s+binary", header):
        assert "label=32" in header, "expects 32-bit labels"
        return np.frombuffer(body, dtype="<i4", count=n, offset=start).astype(np.int64)
    return np.array(body[start : body.index(b")", start)].split(), dtype=np.int64)


case, nparts, name = sys.argv[1], int(sys.argv[2]), sys.argv[3]
owner = read_label_list(f"{case}/constant/polyMesh/owner")
neighbour = read_label_list(f"{case}/constant/polyMesh/neighbour")
ncells = int(max(owner.max(), neighbour.max())) + 1
a, b = owner[: len(neighbour)], neighbour
# Both directions, without duplicates (two cells may share several faces after snappy).
edges = np.unique(np.stack([np.concatenate([a, b]), np.concatenate([b, a])], axis=1), axis=0)
degree = np.bincount(edges[:, 0], minlength=ncells)
offsets = np.concatenate([[0], np.cumsum(degree)])

with tempfile.TemporaryDirectory() as tmp:
    with open(f"{tmp}/mesh.grf", "w") as f:
        # Scotch source graph: version 0, |V| |A|, base 0, flags 000 (no labels, no weights).
        f.write(f"0\n{ncells}\t{len(edges)}\n0\t000\n")
        for c in range(ncells):
            nb = edges[offsets[c] : offsets[c + 1], 1]
            f.write(f"{len(nb)}\t" + "\t".join(map(str, nb)) + "\n")
    # -Cd: deterministic (fixed seed), so make-data.sh reproduces the same pieces.
    subprocess.run(["scotch_gpart", str(nparts), "-Cd", f"{tmp}/mesh.grf", f"{tmp}/mesh.map"], check=True)
    m = np.loadtxt(f"{tmp}/mesh.map", skiprows=1, dtype=np.int64)  # lines: vertex part

part = np.empty(ncells, dtype=np.int64)
part[m[:, 0]] = m[:, 1]
sizes = np.bincount(part, minlength=nparts)
cut = int(np.count_nonzero(part[a] != part[b]))
print(f"scotch_gpart: {ncells} cells, {len(edges) // 2} edges -> {nparts} parts, "
      f"sizes {sizes.min()}..{sizes.max()}, {cut} cut faces")

write_label_list(f"{case}/constant/{name}", part)
