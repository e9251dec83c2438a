"""Memory of a result's numpy views against copies of them, on a pixmap run
whose display mesh has about 10^6 triangles (docs/performance.md#python).

    PYTHONPATH=build/python python3 bench/python_views.py data/cornell_box/cornell_box.obj 2.1
"""

import os
import sys

import numpy as np

import radmesh


def resident_mib():
    return int(open("/proc/self/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def main():
    scene_path, texel = sys.argv[1], float(sys.argv[2])
    r = radmesh.solve(radmesh.read_scene(scene_path), method="pixmap", texel_size=texel, shots=1, hemicube_res=32)
    start = resident_mib()
    views = [r.points, r.triangles, r.patch, r.vertex_radiosity, r.triangle_radiosity]
    after_views = resident_mib()
    copies = [np.array(v) for v in views]
    after_copies = resident_mib()
    print(f"{r.triangles.shape[0]} triangles, {r.points.shape[0]} vertices: views +{after_views - start:.1f} MiB, "
          f"copies +{after_copies - after_views:.1f} MiB (their arrays {sum(c.nbytes for c in copies) / 2**20:.1f} MiB)")


if __name__ == "__main__":
    main()
