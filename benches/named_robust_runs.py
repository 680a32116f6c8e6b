"""The default of `rotavg multiple` against each robust loss a user can name, on generated COLMAP
scenes (`cargo run --release --example colmap_scene -- DIR --cameras N --seed S [...]`; the
committed 36-image scene is `examples/data/colmap_scene`), with no option (the default: since
2026-12-07 `--information auto`, a database's information where it gives one), with weights 1
(`--information kappa`) and with `--information full`:

    python benches/named_robust_runs.py ROTAVG_BINARY DIR [DIR ...]

Each cell is one whole process, `rotavg multiple DIR/database.db --ground-truth DIR/truth --json
--certify none [--information kappa|full] [--loss cauchy|huber|l1]`: the median error in degrees
after the least-squares alignment / after the robust alignment (as `--ground-truth` reports
them), and the process's seconds. Prints a Markdown table (docs/benchmarks.md, "The default
against each robust loss a user can name"). Needs only the Python standard library.
"""

import json
import subprocess
import sys
import time

KAPPA = ["--information", "kappa"]
RUNS = [
    ("no option", []),
    ("weights 1, default", KAPPA),
    ("weights 1, cauchy", KAPPA + ["--loss", "cauchy"]),
    ("weights 1, huber", KAPPA + ["--loss", "huber"]),
    ("weights 1, l1", KAPPA + ["--loss", "l1"]),
    ("information, default", ["--information", "full"]),
    ("information, cauchy", ["--information", "full", "--loss", "cauchy"]),
    ("information, huber", ["--information", "full", "--loss", "huber"]),
    ("information, l1", ["--information", "full", "--loss", "l1"]),
]


def cell(binary, folder, extra):
    start = time.time()
    out = subprocess.run(
        [binary, "multiple", f"{folder}/database.db", "--ground-truth", f"{folder}/truth",
         "--json", "--certify", "none"] + extra,
        capture_output=True, text=True)
    if out.returncode != 0:
        return "error: " + out.stderr.strip().splitlines()[-1]
    accuracy = json.loads(out.stdout)["accuracy"]
    return (f"{accuracy['median_deg']:.3f} / {accuracy['robust']['median_deg']:.3f} "
            f"({time.time() - start:.1f} s)")


def main():
    binary, folders = sys.argv[1], sys.argv[2:]
    print("| scene | " + " | ".join(name for name, _ in RUNS) + " |")
    print("|---" * (len(RUNS) + 1) + "|")
    for folder in folders:
        cells = [cell(binary, folder, extra) for _, extra in RUNS]
        print(f"| {folder} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
