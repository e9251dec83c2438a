"""A mesh-quality study: the smallest angle and the aspect ratio of radmesh's
meshes against the longest edge allowed (max_edge) and the discontinuity
lines (off, contacts, full), as a CSV table and a matplotlib plot.

    PYTHONPATH=build/python python3 examples/python/quality_study.py \
        data/cornell_box/cornell_box.obj out/quality_study [--quick]
"""

import argparse
import csv
import os

import numpy as np

import radmesh


def study(scene, edges, modes):
    rows = []
    for mode in modes:
        for edge in edges:
            mesh = radmesh.mesh(scene, max_edge=edge, discontinuity=mode)
            q = radmesh.quality(mesh)
            shaped = ~q["zero_area"]  # zero-area triangles (closing T-vertices) have no shape to measure
            rows.append({"discontinuity": mode, "max_edge": edge, "triangles": int(mesh.triangles.shape[0]),
                         "min_angle": float(q["min_angle"][shaped].min()),
                         "min_angle_p05": float(np.percentile(q["min_angle"][shaped], 5)),
                         "aspect_p95": float(np.percentile(q["aspect_ratio"][shaped], 95)),
                         "aspect_max": float(q["aspect_ratio"][shaped].max())})
            print("{discontinuity:8} max_edge {max_edge:7.1f}: {triangles:6} triangles, smallest angle "
                  "{min_angle:5.2f} deg, aspect ratio p95 {aspect_p95:.3f}".format(**rows[-1]))
    return rows


def plot(rows, modes, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    for mode in modes:
        mine = [r for r in rows if r["discontinuity"] == mode]
        left.plot([r["triangles"] for r in mine], [r["min_angle"] for r in mine], "o-", label=mode)
        right.plot([r["triangles"] for r in mine], [r["aspect_p95"] for r in mine], "o-", label=mode)
    for ax, label in ((left, "smallest angle (degrees)"), (right, "aspect ratio, 95th percentile")):
        ax.set_xscale("log")
        ax.set_xlabel("triangles")
        ax.set_ylabel(label)
        ax.legend(title="discontinuity")
    fig.suptitle("radmesh mesh quality against max_edge")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene")
    parser.add_argument("out_dir")
    parser.add_argument("--quick", action="store_true", help="three sizes instead of six")
    args = parser.parse_args()
    scene = radmesh.read_scene(args.scene)
    diagonal = float(np.linalg.norm(scene.vertices.max(axis=0) - scene.vertices.min(axis=0)))
    fractions = [1 / 4, 1 / 8, 1 / 16] if args.quick else [1 / 4, 1 / 8, 1 / 12, 1 / 16, 1 / 24, 1 / 32]
    modes = ["off", "contacts", "full"]
    rows = study(scene, [diagonal * f for f in fractions], modes)
    os.makedirs(args.out_dir, exist_ok=True)
    with open(os.path.join(args.out_dir, "quality_study.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, modes, os.path.join(args.out_dir, "quality_study.png"))


if __name__ == "__main__":
    main()
