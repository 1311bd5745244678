"""Writes a cell->part list as an OpenFOAM labelList, the file decomposePar's `method manual`
reads: shared by scotch_partition.py and apc_partition.py."""


def write_label_list(path, labels):
    name = path.replace("\\", "/").rsplit("/", 1)[-1]
    with open(path, "w") as f:
        f.write("FoamFile\n{\n    version 2.0;\n    format ascii;\n    class labelList;\n"
                f"    object {name};\n}}\n{len(labels)}\n(\n")
        f.write("\n".join(map(str, labels)))
        f.write("\n)\n")
