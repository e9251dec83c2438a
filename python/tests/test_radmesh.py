"""The Python module against the radmesh program and closed forms.

Run by ctest (test `python`), which sets RADMESH_CLI (the radmesh program),
RADMESH_DATA (data/) and PYTHONPATH (build/python).
"""

import csv
import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import radmesh

DATA = os.environ.get("RADMESH_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "data"))
CLI = os.environ.get("RADMESH_CLI")
CORNELL = os.path.join(DATA, "cornell_box", "cornell_box.obj")


def without_times(doc):
    if isinstance(doc, dict):
        return {k: without_times(v) for k, v in doc.items() if k not in ("time_seconds", "seconds")}
    if isinstance(doc, list):
        return [without_times(v) for v in doc]
    return doc


@pytest.mark.skipif(not CLI, reason="RADMESH_CLI not set (ctest sets it)")
def test_the_cornell_box_from_python_is_the_programs_bit_for_bit(tmp_path):
    options = {"epsilon": 0.01, "max_edge": 150.0}
    subprocess.run([CLI, "run", CORNELL, "-o", str(tmp_path / "cli"), "-q", "--no-png", "--epsilon", "0.01",
                    "--max-edge", "150"], check=True, capture_output=True)
    result = radmesh.solve(radmesh.read_scene(CORNELL), method="hierarchical", **options)
    written = result.write(tmp_path / "py", png=False)
    assert sorted(os.path.basename(w) for w in written) == ["discontinuities.vtu", "radiosity.vtu", "summary.json"]
    for name in ("radiosity.vtu", "discontinuities.vtu"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    cli_summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert without_times(result.summary()) == without_times(cli_summary)
    # The arrays are the file's: the patch means the summary holds.
    means = result.patch_means()
    for p, entry in enumerate(cli_summary["patches"]):
        assert list(means[p]) == entry["mean_radiosity"]


def test_a_preset_solves_as_the_program_with_the_same_preset(tmp_path):
    # The preset's options, filled in where not named, as `radmesh run --preset`.
    subprocess.run([CLI, "run", CORNELL, "-o", str(tmp_path / "cli"), "-q", "--no-png", "--preset", "draft",
                    "--max-edge", "150"], check=True, capture_output=True)
    result = radmesh.solve(radmesh.read_scene(CORNELL), preset="draft", max_edge=150.0)
    cli_summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert without_times(result.summary()) == without_times(cli_summary)
    assert cli_summary["options"]["preset"] == "draft"
    assert radmesh.methods()[0]["presets"]["draft"] == {"epsilon": "0.01"}
    with pytest.raises(radmesh.InputError, match="preset fine: method matrix has none"):
        radmesh.solve(radmesh.read_scene(CORNELL), method="matrix", preset="fine")


def arrays_of(scene):
    offsets, indices = scene.patches
    return scene.vertices, (offsets, indices), scene.patch_materials, scene.materials


def test_a_scene_from_arrays_solves_as_the_file_does():
    scene = radmesh.read_scene(CORNELL)
    vertices, faces, patch_materials, materials = arrays_of(scene)
    copy = radmesh.Scene.from_arrays(vertices, faces, patch_materials, materials, names=scene.patch_names)
    assert copy.patch_count == scene.patch_count
    assert np.array_equal(copy.vertices, scene.vertices)
    a = radmesh.solve(scene, method="matrix", max_edge=200.0)
    b = radmesh.solve(copy, method="matrix", max_edge=200.0)
    assert np.array_equal(a.patch_means(), b.patch_means())
    assert np.array_equal(a.triangle_radiosity, b.triangle_radiosity)


def test_faces_of_one_size_may_come_as_a_two_dimensional_array():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    scene = radmesh.Scene.from_arrays(square, np.array([[0, 1, 2, 3]]), [0], [{"reflectance": (0.5, 0.5, 0.5)}])
    assert scene.patch_count == 1
    m = radmesh.mesh(scene, max_edge=0.25)
    assert m.triangles.shape[1] == 3 and m.points.shape[1] == 3
    # The mesh covers the square: the areas sum to 1.
    p = m.points[m.triangles]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
    assert area == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("name,rho", [("furnace_cube.obj", 0.5), ("furnace_cube_09.obj", 0.9)])
def test_the_furnace_meets_its_closed_form(name, rho):
    # A closed cube, every face emitting E = 1 and reflecting rho: B = E / (1 - rho) everywhere.
    result = radmesh.solve(radmesh.read_scene(os.path.join(DATA, "furnace_cube", name)), method="matrix",
                           max_edge=0.3)
    assert np.allclose(result.patch_means(), 1.0 / (1.0 - rho), rtol=1e-6, atol=0)
    assert np.allclose(result.vertex_radiosity, 1.0 / (1.0 - rho), rtol=1e-6, atol=0)


def test_result_arrays_are_views_that_keep_the_result_alive():
    result = radmesh.solve(radmesh.read_scene(CORNELL), method="matrix", max_edge=300.0)
    b = result.vertex_radiosity
    assert b.shape == (result.points.shape[0], 3) and b.dtype == np.float64
    assert not b.flags.owndata and not b.flags.writeable
    assert result.triangles.shape == (result.patch.shape[0], 3)
    assert result.triangle_radiosity.shape == (result.patch.shape[0], 3)
    assert result.zero_area.dtype == np.bool_
    assert result.triangles.max() < result.points.shape[0]
    del result
    assert np.isfinite(b).all()  # still valid: the view holds the result


GOOD_VERTICES = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
GOOD_FACES = (np.array([0, 4]), np.array([0, 1, 2, 3]))
GREY = [{"name": "grey", "reflectance": (0.5, 0.5, 0.5)}]


@pytest.mark.parametrize("change,words", [
    ({"vertices": GOOD_VERTICES[:, :2]}, "vertices: shape (n, 3)"),
    ({"vertices": np.array([["a", "b", "c"]] * 4)}, "vertices: an array of numbers"),
    ({"vertices": np.where(np.eye(4, 3) > 0, np.nan, GOOD_VERTICES)}, "vertices[0, 0]: nan"),
    ({"faces": (np.array([0, 4]), np.array([0, 1, 2, 7]))}, "faces indices[3]: 7 is not a vertex index"),
    ({"faces": (np.array([0, 2]), np.array([0, 1]))}, "faces[0]: 2 vertices"),
    ({"faces": (np.array([0, 5]), np.array([0, 1, 2, 3]))}, "faces offsets: the last is 5"),
    ({"patch_materials": [3]}, "patch_materials[0]: 3 is not a material index"),
    ({"patch_materials": [0.5]}, "patch_materials[0]: 0.5 is not an integer"),
    ({"patch_materials": [0, 0]}, "patch_materials: 2 entries for 1 faces"),
    ({"materials": [{"reflectance": (0.5, 0.5)}]}, "materials[0].reflectance: 3 values"),
    ({"materials": [{"reflectance": (1.5, 0.5, 0.5)}]}, "1.5"),
    ({"materials": [{"colour": (0.5, 0.5, 0.5)}]}, "materials[0]: unknown key 'colour'"),
])
def test_bad_arrays_are_input_errors_naming_the_argument(change, words):
    args = {"vertices": GOOD_VERTICES, "faces": GOOD_FACES, "patch_materials": [0], "materials": GREY}
    args.update(change)
    with pytest.raises(radmesh.InputError) as e:
        radmesh.Scene.from_arrays(**args)
    assert words in str(e.value)
    assert isinstance(e.value, ValueError)


def test_arrays_too_large_to_read_are_input_errors_not_crashes():
    huge = np.broadcast_to(np.zeros(3), (2**42, 3))  # a view of 24 bytes standing for 96 TiB
    with pytest.raises(radmesh.InputError, match="vertices: cannot be read"):
        radmesh.Scene.from_arrays(huge, GOOD_FACES, [0], GREY)
    with pytest.raises(radmesh.InputError, match="faces: faces of 0 vertices"):
        radmesh.Scene.from_arrays(GOOD_VERTICES, np.empty((10**12, 0)), [0], GREY)
    with pytest.raises(radmesh.InputError, match="reflectance: 3 values"):
        radmesh.Scene.from_arrays(GOOD_VERTICES, GOOD_FACES, [0], [{"reflectance": 0.5}])


def test_names_that_are_not_utf8_come_back_replaced(tmp_path):
    scene = tmp_path / "latin1.obj"
    scene.write_bytes(b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\no caf\xe9\nusemtl grey\nf 1 2 3\n")
    (tmp_path / "m.mtl").write_text("newmtl grey\nKd 0.5 0.5 0.5\n")
    assert radmesh.read_scene(scene).patch_names == ["caf\ufffd"]  # a pathlib.Path is a path too


def test_errors_carry_the_file_and_the_option(tmp_path):
    with pytest.raises(radmesh.IoError) as e:
        radmesh.read_scene(str(tmp_path / "missing.obj"))
    assert "missing.obj: no such file" in str(e.value) and isinstance(e.value, OSError)
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
    with pytest.raises(radmesh.InputError) as e:
        radmesh.read_scene(str(bad))
    assert "bad.obj:3" in str(e.value)
    scene = radmesh.read_scene(CORNELL)
    with pytest.raises(radmesh.InputError) as e:
        radmesh.solve(scene, epsilon=-1)
    assert e.value.options == ["epsilon"]
    with pytest.raises(radmesh.InputError) as e:
        radmesh.solve(scene, method="matrix", epsilon=0.1)
    assert "epsilon" in str(e.value)
    with pytest.raises(radmesh.InputError) as e:
        radmesh.solve(scene, method="pixmap", max_edge=10.0)
    assert "max_edge is not used by method pixmap" in str(e.value)
    with pytest.raises(radmesh.InputError):
        radmesh.solve(scene, method="nonesuch")
    with pytest.raises(radmesh.InputError) as e:
        radmesh.mesh(scene, threads=1)  # a solve's option, not the meshing's
    assert "threads" in str(e.value)
    # numpy scalars are numbers like any other
    assert radmesh.mesh(scene, max_edge=np.float64(300.0)).max_edge == 300.0


def test_methods_list_their_options_with_units_and_ranges():
    table = {m["name"]: m for m in radmesh.methods()}
    assert list(table)[0] == "hierarchical" and {"matrix", "pixmap"} <= set(table)
    epsilon = next(o for o in table["hierarchical"]["options"] if o["name"] == "epsilon")
    assert epsilon["kind"] == "real" and epsilon["min"] <= epsilon["default"] <= epsilon["max"]
    assert table["pixmap"]["resumable"] and not table["matrix"]["resumable"]
    assert any(o["name"] == "max_edge" and o["unit"] for o in radmesh.meshing_options())
    field = next(o for o in radmesh.solve_options() if o["name"] == "field")
    assert field["kind"] == "choice" and "gather" in field["choices"]


def test_quality_of_a_mesh():
    m = radmesh.mesh(radmesh.read_scene(CORNELL), max_edge=100.0, discontinuity="contacts")
    q = radmesh.quality(m)
    n = m.triangles.shape[0]
    assert q["min_angle"].shape == (n,) and q["aspect_ratio"].shape == (n,)
    total = q["patches"][-1]
    assert total["patch"] == -1 and total["triangles"] == n
    assert total["contact_segments"] == m.contact_segments
    ok = ~q["zero_area"]
    assert total["min_angle"] == pytest.approx(q["min_angle"][ok].min())


def test_progress_is_reported_and_an_error_in_it_stops_the_solve():
    phases = []
    radmesh.solve(radmesh.read_scene(CORNELL), epsilon=0.01, progress=lambda p, f: phases.append((p, f)))
    # Passed on at most ten times a second: a solve of a second or so is heard from a few times.
    assert len(phases) >= 2 and all(0.0 <= f <= 1.0 for _, f in phases)
    assert {p for p, _ in phases} <= {"link", "refine", "solve", "display", "direct", "gather"}

    def refuse(phase, fraction):
        raise RuntimeError("stop here")
    with pytest.raises(RuntimeError, match="stop here"):
        radmesh.solve(radmesh.read_scene(CORNELL), epsilon=0.001, progress=refuse)


def test_ctrl_c_interrupts_a_long_solve_within_a_second_or_so():
    scene = radmesh.read_scene(CORNELL)
    sent = []

    def interrupt():
        time.sleep(0.5)
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)
    threading.Thread(target=interrupt).start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        # Minutes of work at this epsilon: only the interrupt ends it early.
        radmesh.solve(scene, epsilon=1e-5, max_edge=20.0)
    late = time.monotonic() - sent[0]
    assert late < 3.0, f"KeyboardInterrupt came {late:.2f} s after the signal"
    assert time.monotonic() - start < 10.0


def test_a_pixmap_run_written_from_python_resumes(tmp_path):
    scene = radmesh.read_scene(CORNELL)
    first = radmesh.solve(scene, method="pixmap", shots=30, hemicube_res=32)
    written = [os.path.basename(w) for w in first.write(tmp_path, png=False)]
    assert "state.json" in os.listdir(tmp_path / "pixmaps") and "lightmapped.obj" in written
    more = radmesh.solve(scene, method="pixmap", shots=60, hemicube_res=32, resume=tmp_path)
    assert more.summary()["solver"]["shots"] == 60


EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python")


def run_example(name, *args):
    env = dict(os.environ)
    subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args, "--quick"], check=True, env=env,
                   capture_output=True, text=True)


def test_the_quality_study_example_writes_its_table_and_plot(tmp_path):
    pytest.importorskip("matplotlib")
    run_example("quality_study.py", CORNELL, str(tmp_path))
    with open(tmp_path / "quality_study.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 9 and {r["discontinuity"] for r in rows} == {"off", "contacts", "full"}
    assert all(float(r["min_angle"]) > 0 for r in rows)
    assert (tmp_path / "quality_study.png").stat().st_size > 0


def test_the_sweep_example_writes_a_row_per_setting(tmp_path):
    run_example("time_error_sweep.py", CORNELL, str(tmp_path / "sweep.csv"))
    with open(tmp_path / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["method"] for r in rows] == ["hierarchical"] * 2 + ["matrix"] * 2 + ["pixmap"] * 2
    assert all(float(r["worst_patch_error"]) >= float(r["rms_patch_error"]) >= 0 for r in rows)


def test_an_mgf_scene_reads_as_its_obj_and_takes_the_curve_tolerance(tmp_path):
    mgf = radmesh.read_scene(os.path.join(DATA, "cornell_box", "cornell_box.mgf"))
    obj = radmesh.read_scene(CORNELL)
    assert mgf.patch_count == obj.patch_count
    def per_patch(scene):
        return [scene.materials[m]["reflectance"] for m in scene.patch_materials]
    assert np.allclose(per_patch(mgf), per_patch(obj), rtol=0, atol=1e-12)
    ball = tmp_path / "ball.mgf"
    ball.write_text("m white =\n\tc\n\trd 0.5\nv c =\n\tp 0 0 0\nsph c 1\n")
    coarse = radmesh.read_scene(str(ball), curve_tolerance=0.05).patch_count
    fine = radmesh.read_scene(str(ball), curve_tolerance=0.001).patch_count
    assert fine > coarse > 0
    with pytest.raises(radmesh.InputError) as e:
        radmesh.read_scene(str(ball), curve_tolerance=2.0)
    assert e.value.options == ["curve_tolerance"]
