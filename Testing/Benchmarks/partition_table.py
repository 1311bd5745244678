"""Markdown table of the partition benchmark at growing size (run-partition-benchmark.sh scale).

    python3 partition_table.py scale.csv > scale.md

One row per (cells, ranks, partitioner) of apcPartitionBenchmark's CSV: wall seconds (graph,
partition, both), CPU seconds of rank 0 and of the busiest rank (user + system, including MPI's
polling while a rank waits), every rank's peak resident memory, rank 0's over the largest of the other
ranks', edge cut and imbalance. Nothing is typed in by hand.
"""
import csv
import sys


def main(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    rows.sort(key=lambda r: (int(r["cells"]), int(r["ranks"]), r["partitioner"]))
    print("| cells | ranks | K | partitioner | wall s: graph | partition | total | CPU s rank 0 / busiest "
          "| peak MiB per rank (rank 0 first) | rank 0 / others | edge cut | imbalance |")
    print("|---:|---:|---:|---|---:|---:|---:|---|---|---:|---:|---:|")
    for r in rows:
        ratio = "–" if r["ranks"] == "1" else "%.2f" % float(r["rank0_over_others"])
        print("| %s | %s | %s | %s | %.2f | %.2f | %.2f | %.1f / %.1f | %s | %s | %s | %.4f |" % (
            format(int(r["cells"]), ","), r["ranks"], r["K"],
            "METIS (rank 0)" if r["partitioner"] == "metis" else "PT-Scotch",
            float(r["graph_s"]), float(r["partition_s"]), float(r["total_s"]),
            float(r["rank0_cpu_s"]), float(r["max_cpu_s"]),
            r["peak_mib_per_rank"].replace(";", " / "), ratio,
            format(int(r["edge_cut"]), ","), float(r["imbalance"])))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
