"""Time against error: each method at several settings, its patch means
against a fine reference solve, written to a CSV (method, setting, seconds,
worst and RMS relative patch error) that pandas or a spreadsheet reads.

    PYTHONPATH=build/python python3 examples/python/time_error_sweep.py \
        data/cornell_box/cornell_box.obj out/sweep.csv [--quick]
"""

import argparse
import csv
import time

import numpy as np

import radmesh


def errors(means, reference):
    """Worst and area-free RMS relative error over patches and channels (where the reference is lit)."""
    lit = reference > 1e-9 * reference.max()
    rel = np.abs(means[lit] - reference[lit]) / reference[lit]
    return float(rel.max()), float(np.sqrt(np.mean(rel ** 2)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene")
    parser.add_argument("csv")
    parser.add_argument("--quick", action="store_true", help="a coarse reference and two settings per method")
    args = parser.parse_args()
    scene = radmesh.read_scene(args.scene)
    reference = radmesh.solve(scene, method="hierarchical", epsilon=0.01 if args.quick else 2e-4).patch_means()
    sweep = [("hierarchical", {"epsilon": e}) for e in ([0.1, 0.03] if args.quick else [0.1, 0.03, 0.01, 0.003, 0.001])]
    sweep += [("matrix", {"max_edge": m}) for m in ([400.0, 200.0] if args.quick else [400.0, 200.0, 100.0])]
    sweep += [("pixmap", {"shots": s}) for s in ([50, 200] if args.quick else [100, 1000, 5000])]
    with open(args.csv, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["method", "setting", "seconds", "worst_patch_error", "rms_patch_error"])
        for method, options in sweep:
            start = time.perf_counter()
            result = radmesh.solve(scene, method=method, **options)
            seconds = time.perf_counter() - start
            worst, rms = errors(result.patch_means(), reference)
            setting = ",".join(f"{k}={v}" for k, v in options.items())
            writer.writerow([method, setting, f"{seconds:.3f}", f"{worst:.3e}", f"{rms:.3e}"])
            print(f"{method:12} {setting:16} {seconds:7.2f} s  worst {worst:.2%}  rms {rms:.2%}")


if __name__ == "__main__":
    main()
