"""A scene scaled by 1e-4 or 1e4, or moved by 1e6, against the scene as it is: whether
the initial mesh has the same triangles, and the largest relative difference of any lit
patch mean (the field users see, and the element values), per method
(docs/accuracy.md#scaled-and-moved-scenes).

    PYTHONPATH=build/python python3 bench/scaled_scenes.py data/cornell_box/cornell_box.obj
"""

import sys

import numpy as np

import radmesh

RUNS = [
    ("matrix, field=mean", dict(method="matrix", field="mean")),
    ("matrix", dict(method="matrix")),
    ("hierarchical", dict(method="hierarchical")),
    ("pixmap", dict(method="pixmap")),
]
MAPS = [("scaled 1e-4", 1e-4, 0.0), ("scaled 1e4", 1e4, 0.0), ("moved 1e6", 1.0, 1e6)]


def worst(a, b):
    lit = a > 1e-9
    return float(np.max(np.abs(b[lit] / a[lit] - 1.0))) if lit.any() else 0.0


def main():
    scene = radmesh.read_scene(sys.argv[1])
    offsets, indices = scene.patches

    def mapped(scale, shift):
        return radmesh.Scene.from_arrays(scene.vertices * scale + shift, (offsets, indices), scene.patch_materials,
                                         scene.materials, names=scene.patch_names)

    base_mesh = radmesh.mesh(scene)
    for what, scale, shift in MAPS:
        m = radmesh.mesh(mapped(scale, shift))
        same = np.array_equal(np.asarray(m.triangles), np.asarray(base_mesh.triangles))
        print(f"initial mesh, {what}: {'same triangles' if same else 'different triangles'}")
    for name, options in RUNS:
        base = radmesh.solve(scene, **options)
        field, elements = base.patch_means(), base.element_patch_means()
        cells = []
        for what, scale, shift in MAPS:
            r = radmesh.solve(mapped(scale, shift), **options)
            cells.append(f"{what}: field {worst(field, r.patch_means()):.2g}, "
                         f"elements {worst(elements, r.element_patch_means()):.2g}")
        print(f"{name}: " + "; ".join(cells))


if __name__ == "__main__":
    main()
