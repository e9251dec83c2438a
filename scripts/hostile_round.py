#!/usr/bin/env python3
"""A hostile round: runs the radmesh program on hundreds of malformed, extreme
and adversarial inputs, as a hostile user would, and classifies each outcome.

    python3 scripts/hostile_round.py [--radmesh build/cli/radmesh] [--out DIR] [--timeout S] [--only SUBSTRING]

Every case names what a correct program does:
  ok      the run succeeds: exit 0, summary.json with finite numbers (no null
          but an error bound), radiosity.vtu written;
  same    as ok, and every object's mean radiosity equals, within the case's
          tolerance, a reference run's (the physics is invariant: the scene
          scaled, moved, its emission scaled);
  error   the input is bad: exit 1 (bad input) or 2 (usage) with a message
          whose last line says "radmesh: error:" (or CLI11's usage line), and
          nothing of the run left in its output folder;
  either  random damage (a truncation, a flipped byte): ok or error.
Outcomes: right (as named), clear-error, crash (a signal or exit 3 or more),
hang (past the timeout), wrong (an error case that ran, non-finite output, or
a 'same' case whose means differ), leftover (a failed run that left files).
Writes DIR/cases.csv and prints the table; exits 1 if any case is crash, hang,
wrong or leftover. Standard library only.
"""

import argparse
import csv
import json
import math
import os
import random
import re
import resource
import shutil
import struct
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, "data")


# ---------------------------------------------------------------- scenes

def read(path, mode="r"):
    with open(path, mode) as f:
        return f.read()


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb" if isinstance(text, bytes) else "w") as f:
        f.write(text)
    return path


BOX_OBJ = read(os.path.join(DATA, "box_on_floor", "box_on_floor.obj"))
BOX_MTL = read(os.path.join(DATA, "box_on_floor", "box_on_floor.mtl"))
CORNELL_OBJ = read(os.path.join(DATA, "cornell_box", "cornell_box.obj"))
CORNELL_MTL = read(os.path.join(DATA, "cornell_box", "cornell_box.mtl"))


def box_vertices_faces():
    """The box-on-floor scene's vertices and faces (1-based) by object."""
    verts, objects, name = [], {}, None
    for line in BOX_OBJ.splitlines():
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            verts.append(tuple(float(x) for x in t[1:4]))
        elif t[0] == "o":
            name = t[1]
            objects[name] = []
        elif t[0] == "f":
            objects[name].append([int(x) for x in t[1:]])
    return verts, objects


def triangles_of(objects, names):
    tris = []
    for n in names:
        for f in objects[n]:
            for k in range(1, len(f) - 1):
                tris.append((f[0] - 1, f[k] - 1, f[k + 1] - 1))
    return tris


def ply_ascii(verts, tris):
    out = ["ply", "format ascii 1.0", "element vertex %d" % len(verts), "property float x", "property float y",
           "property float z", "element face %d" % len(tris), "property list uchar int vertex_indices", "end_header"]
    out += ["%r %r %r" % v for v in verts]
    out += ["3 %d %d %d" % t for t in tris]
    return "\n".join(out) + "\n"


def ply_binary(verts, tris):
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
            "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n"
            % (len(verts), len(tris))).encode()
    body = b"".join(struct.pack("<3f", *v) for v in verts)
    body += b"".join(struct.pack("<B3i", 3, *t) for t in tris)
    return head + body


def off_text(verts, tris):
    out = ["OFF", "%d %d 0" % (len(verts), len(tris))]
    out += ["%r %r %r" % v for v in verts]
    out += ["3 %d %d %d" % t for t in tris]
    return "\n".join(out) + "\n"


def stl_ascii(verts, tris):
    out = ["solid s"]
    for a, b, c in tris:
        out += ["facet normal 0 0 0", "outer loop"]
        out += ["vertex %r %r %r" % verts[i] for i in (a, b, c)]
        out += ["endloop", "endfacet"]
    return "\n".join(out + ["endsolid s"]) + "\n"


def stl_binary(verts, tris, count=None):
    body = b"".join(struct.pack("<12fH", 0, 0, 0, *verts[a], *verts[b], *verts[c], 0) for a, b, c in tris)
    return b"\0" * 80 + struct.pack("<I", len(tris) if count is None else count) + body


def gltf(verts, tris, nodes=None, scene_nodes=None, stride=None, index_count=None, indices=None):
    vb = b"".join(struct.pack("<3f", *v) for v in verts)
    idx = indices if indices is not None else [i for t in tris for i in t]
    ib = b"".join(struct.pack("<I", i) for i in idx)
    import base64
    uri = "data:application/octet-stream;base64," + base64.b64encode(vb + ib).decode()
    lo = [min(v[k] for v in verts) for k in range(3)]
    hi = [max(v[k] for v in verts) for k in range(3)]
    view0 = {"buffer": 0, "byteOffset": 0, "byteLength": len(vb)}
    if stride is not None:
        view0["byteStride"] = stride
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": uri, "byteLength": len(vb) + len(ib)}],
        "bufferViews": [view0, {"buffer": 0, "byteOffset": len(vb), "byteLength": len(ib)}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(verts), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": len(idx) if index_count is None else index_count,
             "type": "SCALAR"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": nodes if nodes is not None else [{"mesh": 0}],
        "scenes": [{"nodes": scene_nodes if scene_nodes is not None else [0]}],
        "scene": 0,
    }
    return json.dumps(doc)


def json_scene(mesh_file, material="grey", extra=""):
    return ('{"materials": {"grey": {"reflectance": [0.5, 0.5, 0.5]}}, "objects": [{"file": "room.obj"}, '
            '{"file": "%s", "material": "%s"%s}]}' % (mesh_file, material, extra))


def room_obj():
    """The floor and lamp of box_on_floor (the box comes from the mesh file)."""
    lines, keep = [], True
    for line in BOX_OBJ.splitlines():
        if line.startswith("o "):
            keep = line.split()[1] != "box"
        if keep:
            lines.append(line)
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- running

def snapshot(folder):
    """Every file under `folder`: relative name -> content."""
    out = {}
    for base, _, names in os.walk(folder):
        for n in names:
            p = os.path.join(base, n)
            out[os.path.relpath(p, folder)] = read(p, "rb")
    return out


class Runner:
    def __init__(self, exe, out, timeout):
        self.exe, self.out, self.timeout = exe, out, timeout
        self.rows = []
        self.references = {}

    def run(self, name, category, expect, args, scene_dir=None, limit_fsize=None, compare=None, tolerance=0.0,
            unchanged=None):
        work = os.path.join(self.out, "runs", name)
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        out_dir = os.path.join(work, "out")
        argv = [self.exe] + [a.replace("OUT", out_dir).replace("SCENES", scene_dir or "") for a in args]
        if "-o" not in argv and "mesh" not in args[:1] and "quality" not in args[:1]:
            argv += ["-o", out_dir]
        if not any(a in argv for a in ("-q", "--quiet")):
            argv.append("-q")
        if args[:1] == ["run"] and "--no-png" not in argv:
            argv.append("--no-png")

        def limits():
            if limit_fsize is not None:
                resource.setrlimit(resource.RLIMIT_FSIZE, (limit_fsize, limit_fsize))

        before = snapshot(unchanged) if unchanged else None
        env = dict(os.environ, DISPLAY="")
        try:
            p = subprocess.run(argv, capture_output=True, text=True, errors="replace", timeout=self.timeout,
                               preexec_fn=limits, env=env)
            rc, err = p.returncode, p.stderr
        except subprocess.TimeoutExpired:
            rc, err = None, ""
        outcome, detail = self.classify(expect, rc, err, out_dir, compare, tolerance)
        if before is not None and snapshot(unchanged) != before:
            outcome, detail = "wrong", "changed the folder it only reads: " + unchanged
        self.rows.append({"case": name, "category": category, "expect": expect, "exit": "timeout" if rc is None else rc,
                          "outcome": outcome, "detail": detail[:300]})
        return out_dir

    def classify(self, expect, rc, err, out_dir, compare, tolerance):
        if rc is None:
            return "hang", "past the timeout"
        if rc < 0 or rc >= 3:
            last = err.strip().splitlines()[-1] if err.strip() else ""
            return "crash", "exit %d: %s" % (rc, last)
        files = []
        for base, _, names in os.walk(out_dir):
            files += [os.path.join(base, n) for n in names]
        if rc in (1, 2):
            last = err.strip().splitlines()[-1] if err.strip() else ""
            if files:
                return "leftover", "exit %d left %s" % (rc, ", ".join(os.path.relpath(f, out_dir) for f in files[:4]))
            clear = last.startswith("radmesh: error:") or (rc == 2 and ("--" in err or "Run with --help" in err or
                                                                         "required" in err))
            if not clear:
                return "wrong", "unclear message: " + last
            if expect in ("ok", "same"):
                return "wrong", "refused a valid input: " + last
            return "clear-error", last
        # rc == 0
        if expect == "error":
            return "wrong", "accepted a bad input"
        if any(f.endswith(".tmp") for f in files):
            return "leftover", "a .tmp file"
        summary = os.path.join(out_dir, "summary.json")
        if not os.path.exists(summary):
            return "wrong", "no summary.json"
        text = read(summary)
        if re.search(r"\bNaN\b|\binf\b|\bInfinity\b", text):
            return "wrong", "a non-finite number in summary.json"
        doc = json.loads(text)
        bad = []

        def walk(x, path):
            if x is None and "error_bound" not in path:
                bad.append(path)
            elif isinstance(x, dict):
                for k, v in x.items():
                    walk(v, path + "." + k)
            elif isinstance(x, list):
                for i, v in enumerate(x):
                    walk(v, path + "[%d]" % i)
        walk(doc, "")
        if bad:
            return "wrong", "null in summary.json at " + bad[0]
        if compare is not None:
            ref_doc, factor = compare
            means = {o["name"]: o.get("mean_radiosity") for o in doc["objects"]}
            worst = 0.0
            for o in ref_doc["objects"]:
                r = o.get("mean_radiosity")
                m = means.get(o["name"])
                if r is None or m is None:
                    continue
                for c in range(3):
                    if r[c] * factor != 0.0:
                        worst = max(worst, abs(m[c] / (r[c] * factor) - 1.0))
            if worst > tolerance:
                return "wrong", "object means off by %.3g (tolerance %.3g)" % (worst, tolerance)
            return "right", "object means within %.3g" % worst
        return "right", "finite results"


# ---------------------------------------------------------------- cases

NUMBER_TOKENS = ["0x1p0", "0x10", "1" + "0" * 330, "0." + "0" * 330 + "1", "1e400", "-1e400", "1e-400", "nan", "NaN",
                 "inf", "-inf", "+1", "1e", "1.2.3", "1,5", "--1", "", ".", "1_0", "1e+", "0e0", "1d0", "\u00a01",
                 "1x", "4.9e-324"]
# Tokens of the syntax: read as the double nearest their value (below the
# smallest double, 0), as docs/scenes.md says.
READ_AS_WRITTEN = ("0e0", "1e-400", "4.9e-324")


def reader_cases(r, rnd, work):
    verts, objects = box_vertices_faces()
    room = room_obj()
    box_tris = triangles_of(objects, ["box"])
    box_idx = sorted({i for t in box_tris for i in t})
    remap = {v: k for k, v in enumerate(box_idx)}
    bverts = [verts[i] for i in box_idx]
    btris = [tuple(remap[i] for i in t) for t in box_tris]
    fast = ["--method", "matrix", "--max-edge", "1", "--discontinuity", "contacts", "--rays", "4"]

    # OBJ: number syntax in vertex, Kd and Ke lines; truncations; byte flips.
    base = os.path.join(work, "obj")
    lines = BOX_OBJ.splitlines()
    vlines = [i for i, l in enumerate(lines) if l.startswith("v ")]
    for k, tok in enumerate(NUMBER_TOKENS):
        d = os.path.join(base, "num%d" % k)
        mod = lines[:]
        i = vlines[k % len(vlines)]
        t = mod[i].split()
        t[1 + k % 3] = tok
        mod[i] = " ".join(t)
        write(os.path.join(d, "box_on_floor.mtl"), BOX_MTL)
        write(os.path.join(d, "s.obj"), "\n".join(mod) + "\n")
        expect = "ok" if tok in READ_AS_WRITTEN else "error"
        r.run("obj_number_%d" % k, "reader: OBJ number syntax (%r)" % tok[:12], expect, ["run", d + "/s.obj"] + fast)
    mlines = BOX_MTL.splitlines()
    for k, tok in enumerate(NUMBER_TOKENS):
        d = os.path.join(base, "mtl%d" % k)
        mod = [(" ".join(l.split()[:1] + [tok] * 3) if l.startswith("Kd") else l) for l in mlines]
        write(os.path.join(d, "box_on_floor.mtl"), "\n".join(mod) + "\n")
        write(os.path.join(d, "s.obj"), BOX_OBJ)
        expect = "ok" if tok in READ_AS_WRITTEN else "error"
        r.run("mtl_number_%d" % k, "reader: MTL number syntax (%r)" % tok[:12], expect, ["run", d + "/s.obj"] + fast)
    for k in range(25):
        d = os.path.join(base, "cut%d" % k)
        cut = rnd.randrange(1, len(BOX_OBJ))
        write(os.path.join(d, "box_on_floor.mtl"), BOX_MTL)
        write(os.path.join(d, "s.obj"), BOX_OBJ[:cut])
        r.run("obj_truncated_%d" % k, "reader: OBJ truncated", "either", ["run", d + "/s.obj"] + fast)
    for k in range(25):
        d = os.path.join(base, "flip%d" % k)
        data = bytearray(BOX_OBJ.encode())
        for _ in range(3):
            data[rnd.randrange(len(data))] = rnd.randrange(256)
        write(os.path.join(d, "box_on_floor.mtl"), BOX_MTL)
        write(os.path.join(d, "s.obj"), bytes(data))
        r.run("obj_flipped_%d" % k, "reader: OBJ bytes flipped", "either", ["run", d + "/s.obj"] + fast)
    d = os.path.join(base, "bom")
    write(os.path.join(d, "box_on_floor.mtl"), b"\xef\xbb\xbf" + BOX_MTL.encode())
    write(os.path.join(d, "s.obj"), b"\xef\xbb\xbf" + BOX_OBJ.encode())
    r.run("obj_mtl_bom", "reader: OBJ and MTL with a UTF-8 byte-order mark", "ok", ["run", d + "/s.obj"] + fast)
    d = os.path.join(base, "twice")
    write(os.path.join(d, "box_on_floor.mtl"), BOX_MTL)
    write(os.path.join(d, "s.obj"), "mtllib box_on_floor.mtl\n" + BOX_OBJ)
    r.run("obj_mtllib_twice", "reader: one MTL library loaded twice", "ok", ["run", d + "/s.obj"] + fast)
    d = os.path.join(base, "space")
    write(os.path.join(d, "box_on_floor.mtl"), BOX_MTL.replace("newmtl white", "newmtl white paint"))
    write(os.path.join(d, "s.obj"), BOX_OBJ.replace("usemtl white", "usemtl white paint"))
    r.run("mtl_name_with_space", "reader: an MTL material name with a space", "either", ["run", d + "/s.obj"] + fast)
    d = os.path.join(base, "empty")
    write(os.path.join(d, "s.obj"), "")
    r.run("obj_empty", "reader: an empty OBJ", "error", ["run", d + "/s.obj"] + fast)

    # Mesh files through a JSON scene.
    meshes = {
        "ply": ply_ascii(bverts, btris), "plyb": ply_binary(bverts, btris), "off": off_text(bverts, btris),
        "stl": stl_ascii(bverts, btris), "stlb": stl_binary(bverts, btris), "gltf": gltf(bverts, btris),
    }
    ext = {"ply": "ply", "plyb": "ply", "off": "off", "stl": "stl", "stlb": "stl", "gltf": "gltf"}

    def mesh_run(name, category, expect, fmt, content, extra=""):
        d = os.path.join(work, "mesh", name)
        write(os.path.join(d, "room.obj"), room.replace("mtllib box_on_floor.mtl", "mtllib room.mtl"))
        write(os.path.join(d, "room.mtl"), BOX_MTL)
        write(os.path.join(d, "box." + ext[fmt]), content)
        write(os.path.join(d, "scene.json"), json_scene("box." + ext[fmt], extra=extra))
        r.run(name, category, expect, ["run", d + "/scene.json"] + fast)

    for fmt, content in meshes.items():
        mesh_run("mesh_%s_valid" % fmt, "reader: %s, valid" % fmt, "ok", fmt, content)
        raw = content.encode() if isinstance(content, str) else content
        for k in range(12):
            cut = rnd.randrange(1, len(raw))
            mesh_run("mesh_%s_truncated_%d" % (fmt, k), "reader: %s truncated" % fmt, "either", fmt, raw[:cut])
        for k in range(10):
            data = bytearray(raw)
            for _ in range(2):
                data[rnd.randrange(len(data))] = rnd.randrange(256)
            mesh_run("mesh_%s_flipped_%d" % (fmt, k), "reader: %s bytes flipped" % fmt, "either", fmt, bytes(data))
    # Counts that the file cannot hold, and data past the counts.
    ply = meshes["ply"]
    mesh_run("ply_count_huge", "reader: PLY vertex count 2^31", "error", "ply",
             ply.replace("element vertex %d" % len(bverts), "element vertex 2147483647"))
    plyb = bytearray(meshes["plyb"])
    head_end = plyb.index(b"end_header\n") + len(b"end_header\n")
    first_face = head_end + 12 * len(bverts)
    plyb[first_face] = 255
    mesh_run("plyb_list_huge", "reader: binary PLY face list of 255", "error", "plyb", bytes(plyb))
    claim = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n").encode()
    claim += struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<i", 1 << 26) + struct.pack("<3i", 0, 1, 2)
    mesh_run("plyb_list_2_26", "reader: binary PLY face claiming 2^26 vertices", "error", "plyb", claim)
    mesh_run("plyb_zero_vertices", "reader: PLY with no vertices", "error", "ply",
             "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 0\nproperty list uchar int vertex_indices\nend_header\n")
    off = meshes["off"]
    mesh_run("off_extra_faces", "reader: OFF with more faces than declared", "error", "off",
             off + "3 0 1 2\n")
    mesh_run("off_count_huge", "reader: OFF counts past the file", "error", "off",
             off.replace("%d %d 0" % (len(bverts), len(btris)), "99999999 99999999 0"))
    mesh_run("stlb_count_huge", "reader: binary STL facet count 2^32-1", "error", "stlb",
             stl_binary(bverts, btris, count=0xFFFFFFFF))
    # glTF: node trees, indices, strides.
    deep = [{"children": [k + 1]} for k in range(20000)] + [{"mesh": 0}]
    mesh_run("gltf_deep_nodes", "reader: glTF nodes nested 20,000 deep", "error", "gltf", gltf(bverts, btris, nodes=deep))
    cyc = [{"children": [1]}, {"children": [0], "mesh": 0}]
    mesh_run("gltf_cyclic_nodes", "reader: glTF nodes in a cycle", "error", "gltf", gltf(bverts, btris, nodes=cyc))
    wide = [{"children": list(range(1, 200001))}] + [{"mesh": 0}] * 200000
    mesh_run("gltf_wide_nodes", "reader: glTF with 200,000 nodes", "either", "gltf", gltf(bverts, btris, nodes=wide))
    idx = [i for t in btris for i in t]
    bad = idx[:]
    bad[0] = 9999
    mesh_run("gltf_index_range", "reader: glTF index out of range", "error", "gltf",
             gltf(bverts, btris, indices=bad))
    mesh_run("gltf_index_count", "reader: glTF index count not a multiple of 3", "error", "gltf",
             gltf(bverts, btris, indices=idx + [0]))
    mesh_run("gltf_stride_small", "reader: glTF byteStride smaller than its element", "error", "gltf",
             gltf(bverts, btris, stride=4))
    mesh_run("gltf_count_past_buffer", "reader: glTF accessor count past its buffer", "error", "gltf",
             gltf(bverts, btris, index_count=len(idx) * 1000))
    # JSON scene values.
    for k, extra in enumerate([', "transform": {"scale": 0}', ', "transform": {"scale": 1e400}',
                               ', "transform": {"scale": "big"}', ', "transform": {"translate": [1, 2]}',
                               ', "transform": {"rotate_deg": [0, 0, NaN]}', ', "colour": 1',
                               ', "transform": {"translate": [1e20, 0, 0]}']):
        mesh_run("json_value_%d" % k, "reader: JSON scene value (%s)" % extra[2:40], "error", "ply", ply, extra)
    d = os.path.join(work, "json_nul")
    write(os.path.join(d, "scene.json"), '{"materials": {}, "objects": [{"file": "a\\u0000b.obj"}]}')
    r.run("json_nul_file_name", "reader: JSON scene file name with a NUL", "error", ["run", d + "/scene.json"])
    d = os.path.join(work, "json_deep")
    write(os.path.join(d, "scene.json"), "[" * 100000 + "]" * 100000)
    r.run("json_deep", "reader: JSON nested 100,000 deep", "error", ["run", d + "/scene.json"])


def option_cases(r, work):
    scene = os.path.join(DATA, "parallel_plates", "parallel_plates.obj")
    help_text = subprocess.run([r.exe, "run", "--help"], capture_output=True, text=True).stdout
    flags = sorted(set(re.findall(r"^\s+(?:-\w,)?(--[a-z][a-z-]*)", help_text, re.M)))
    values = ["-1", "0", "1e999", "nan", "inf", "-inf", "abc", "", "0x10", "1" + "0" * 400, "2147483648", "1e-320"]
    skip = {"--help", "--output", "--probe", "--resume", "--no-png", "--quiet", "--export-links", "--method"}
    for flag in flags:
        if flag in skip:
            continue
        for k, v in enumerate(values):
            name = "option_%s_%d" % (flag.strip("-").replace("-", "_"), k)
            r.run(name, "option: %s %r" % (flag, v[:12]), "either", ["run", scene, flag, v, "--method",
                                                                      method_for(flag, help_text)])
    for k, (args, expect) in enumerate([
            (["--method", "pixmap", "--rays", "4"], "error"), (["--method", "matrix", "--epsilon", "0.1"], "error"),
            (["--method", "pixmap", "--max-edge", "1"], "error"), (["--method", "pixmap", "--tolerance", "0.1"], "error"),
            (["--method", "nope"], "error"), (["--field", "texels"], "error"), (["--nodal", "fit", "--field", "mean"], "error"),
            (["--method", "pixmap", "--hemicube-res", "16384", "--max-memory", "1"], "error"),
            (["--method", "pixmap", "--hemicube-res", "15"], "error"), (["--method", "matrix", "--resume", "/tmp"], "error"),
            (["--method", "pixmap", "--field", "gather", "--rays", "4", "--shots", "20", "--hemicube-res", "32"], "ok"),
            (["--threads", "1"], "ok"), (["--threads", "4096"], "ok"), (["--epsilon", "1e-9", "--max-memory", "0.05"], "error"),
            (["--max-edge", "1e-300"], "error"), (["--min-angle", "30"], "ok")]):
        r.run("option_combo_%d" % k, "option: " + " ".join(args), expect, ["run", scene] + args)


def method_for(flag, help_text):
    """The method that takes a method option, per --help ('with --method X')."""
    m = re.search(re.escape(flag) + r"[^\n]*\n?\s*with --method ([a-z]+)", help_text)
    return m.group(1) if m else "hierarchical"


def physics_cases(r, work):
    """Scaled, moved and re-lit scenes against their reference: the same physics."""
    # Options that do not depend on the unit (the matrix method's mesh is
    # its default, a fraction of the scene's size).
    methods = {"hierarchical": ["--epsilon", "0.02"], "matrix": ["--discontinuity", "contacts"],
               "pixmap": ["--hemicube-res", "64"]}
    tolerance = {"hierarchical": 0.03, "matrix": 0.06, "pixmap": 0.03}

    def variant(name, transform=None, emission=None):
        d = os.path.join(work, "physics", name)
        out = []
        for line in BOX_OBJ.splitlines():
            if line.startswith("v ") and transform:
                out.append("v %.17g %.17g %.17g" % transform(tuple(float(x) for x in line.split()[1:4])))
            else:
                out.append(line)
        write(os.path.join(d, "s.obj"), "\n".join(out) + "\n")
        mtl = BOX_MTL
        if emission is not None:
            mtl = re.sub(r"^Ke (\S+) (\S+) (\S+)", lambda m: "Ke " + " ".join(repr(float(x) * emission) for x in m.groups()),
                         mtl, flags=re.M)
        write(os.path.join(d, "box_on_floor.mtl"), mtl)
        return d + "/s.obj"

    base = variant("base")
    refs = {}
    for m, opts in methods.items():
        out = r.run("physics_%s_reference" % m, "physics: %s reference" % m, "ok", ["run", base, "--method", m] + opts)
        refs[m] = json.loads(read(os.path.join(out, "summary.json")))
    cases = [("scaled_%s" % s, (lambda f: lambda v: tuple(f * x for x in v))(float(s)), None, 1.0)
             for s in ["1e-12", "1e-6", "1e6", "1e12", "1e40"]]
    cases += [("moved_%s" % s, (lambda f: lambda v: (v[0] + f, v[1], v[2] + f))(float(s)), None, 1.0)
              for s in ["1e3", "1e6", "1e9"]]
    cases += [("emission_%s" % s, None, float(s), float(s)) for s in ["1e-300", "1e-30", "1e30", "1e45"]]
    for name, transform, emission, factor in cases:
        path = variant(name, transform, emission)
        for m, opts in methods.items():
            r.run("physics_%s_%s" % (name, m), "physics: %s, %s" % (name.replace("_", " "), m), "same",
                  ["run", path, "--method", m] + opts, compare=(refs[m], factor), tolerance=tolerance[m])
    for name, transform in [("moved_1e20", lambda v: (v[0] + 1e20, v[1], v[2]))]:
        path = variant(name, transform)
        r.run("physics_%s" % name, "physics: moved 1e20 (below double's resolution)", "error", ["run", path])
    d = os.path.join(work, "physics", "subnormal")
    write(os.path.join(d, "s.obj"), BOX_OBJ)
    write(os.path.join(d, "box_on_floor.mtl"), re.sub(r"^Ke .*$", "Ke 5e-324 5e-324 5e-324", BOX_MTL, flags=re.M))
    r.run("physics_subnormal_emission", "physics: subnormal emission", "error", ["run", d + "/s.obj"])


def output_cases(r, work):
    scene = os.path.join(DATA, "box_on_floor", "box_on_floor.obj")
    a_file = write(os.path.join(work, "out_is_a_file"), "x")
    r.run("output_is_a_file", "output: -o names a file", "error", ["run", scene, "-o", a_file])
    ro = os.path.join(work, "read_only")
    os.makedirs(ro, exist_ok=True)
    os.chmod(ro, 0o500)
    if os.geteuid() != 0:
        r.run("output_read_only", "output: -o in a read-only folder", "error", ["run", scene, "-o", ro + "/x"])
    methods = {"hierarchical": ["--epsilon", "0.02", "--export-links"],
               "matrix": ["--max-edge", "1", "--discontinuity", "contacts"],
               "pixmap": ["--hemicube-res", "32", "--shots", "30"]}
    for m, opts in methods.items():
        # A file-size limit (ulimit -f) holds for each file: below the run's
        # largest file the run fails and leaves nothing; at it, it succeeds.
        whole = r.run("output_whole_%s" % m, "output: no limit, %s" % m, "ok", ["run", scene, "--method", m] + opts)
        largest = max(os.path.getsize(os.path.join(b, n)) for b, _, ns in os.walk(whole) for n in ns)
        for size in sorted({0, 1000, largest // 3, largest // 2, largest - 4096, largest - 1}):
            if size >= 0:
                r.run("output_full_%s_%d" % (m, size), "output: files limited to %d bytes, %s" % (size, m), "error",
                      ["run", scene, "--method", m] + opts, limit_fsize=size)
        r.run("output_fits_%s" % m, "output: files limited to the largest, %s" % m, "ok",
              ["run", scene, "--method", m] + opts, limit_fsize=largest)


def state_cases(r, rnd, work):
    """--resume from a damaged, foreign or missing state, and hostile probe files."""
    scene = os.path.join(DATA, "box_on_floor", "box_on_floor.obj")
    opts = ["--method", "pixmap", "--hemicube-res", "32"]
    saved = r.run("state_saved", "state: a pixmap run that saves its state", "ok", ["run", scene] + opts + ["--shots", "20"])
    state = os.path.join(saved, "pixmaps", "state.json")
    vti = os.path.join(saved, "pixmaps", "pixmap_0.vti")

    def damaged(name, damage):
        d = os.path.join(work, "state", name)
        shutil.rmtree(d, ignore_errors=True)
        shutil.copytree(saved, d)
        damage(d)
        return d

    def flip(path, count):
        def do(d):
            p = os.path.join(d, os.path.relpath(path, saved))
            data = bytearray(read(p, "rb"))
            for _ in range(count):
                data[rnd.randrange(len(data))] = rnd.randrange(256)
            write(p, bytes(data))
        return do

    def cut(path, keep):
        def do(d):
            p = os.path.join(d, os.path.relpath(path, saved))
            data = read(p, "rb")
            write(p, data[:int(len(data) * keep)])
        return do

    def remove(path):
        return lambda d: os.remove(os.path.join(d, os.path.relpath(path, saved)))

    cases = [("state_json_cut_%d" % k, cut(state, f), "error") for k, f in enumerate([0.0, 0.3, 0.9])]
    cases += [("state_json_flipped_%d" % k, flip(state, 2), "either") for k in range(12)]
    cases += [("state_vti_cut_%d" % k, cut(vti, f), "error") for k, f in enumerate([0.0, 0.5, 0.99])]
    cases += [("state_vti_flipped_%d" % k, flip(vti, 3), "either") for k in range(12)]
    cases += [("state_vti_missing", remove(vti), "error"), ("state_json_missing", remove(state), "error")]

    def edit(old, new):
        def do(d):
            p = os.path.join(d, "pixmaps", "state.json")
            write(p, read(p).replace(old, new, 1))
        return do

    def swap(a, b):
        def do(d):
            pa, pb = (os.path.join(d, "pixmaps", "pixmap_%d.vti" % k) for k in (a, b))
            data = read(pa, "rb")
            write(pa, read(pb, "rb"))
            write(pb, data)
        return do
    cases += [("state_json_shots_edited", edit('"shots": 20', '"shots": 21'), "error"),
              ("state_json_power_edited", edit('"power_absorbed": [\n    0.', '"power_absorbed": [\n    1.'), "error"),
              ("state_vti_swapped", swap(1, 2), "error")]
    for name, damage, expect in cases:
        d = damaged(name, damage)
        r.run(name, "state: --resume from %s" % name[6:].replace("_", " "), expect,
              ["run", scene] + opts + ["--shots", "40", "--resume", d], unchanged=d)
    d = damaged("state_intact", lambda d: None)
    r.run("state_other_scene", "state: --resume with another scene", "error",
          ["run", os.path.join(DATA, "cornell_box", "cornell_box.obj")] + opts + ["--shots", "40", "--resume", d],
          unchanged=d)
    r.run("state_other_options", "state: --resume with another hemicube", "error",
          ["run", scene, "--method", "pixmap", "--hemicube-res", "64", "--shots", "40", "--resume", d], unchanged=d)
    r.run("state_fewer_shots", "state: --resume to fewer shots than made", "either",
          ["run", scene] + opts + ["--shots", "10", "--resume", d], unchanged=d)
    r.run("state_continued", "state: --resume intact", "ok", ["run", scene] + opts + ["--shots", "40", "--resume", d],
          unchanged=d)

    good = "a 1.5 0 1.5 0 1 0\n"  # on the floor, beside the box
    probes = {"nan": "a nan 0 0 0 0 1\n", "short": "a 0 0 0 0 1\n", "zero_normal": "a 0 0 0 0 0 0\n",
              "far": "a 1e300 0 0 0 1 0\n", "hex": "a 0x1p0 0 0 0 0 1\n", "empty": "",
              "binary": "\x00\x01\x02\xff\n", "long_label": "x" * 100000 + " 1.5 0 1.5 0 1 0\n",
              "many": good * 20000, "valid": good}
    for name, text in probes.items():
        f = write(os.path.join(work, "probes", name + ".txt"), text)
        expect = "ok" if name in ("valid", "many", "long_label") else "either" if name == "empty" else "error"
        r.run("probe_" + name, "state: probe file (%s)" % name.replace("_", " "), expect,
              ["run", scene, "--method", "matrix", "--max-edge", "1", "--probe", f])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--radmesh", default=os.path.join(ROOT, "build", "cli", "radmesh"))
    ap.add_argument("--out", default=os.path.join(ROOT, "hostile-out"))
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--only", default="", help="only the case groups whose name contains this (reader, option, physics, output, state)")
    a = ap.parse_args()
    shutil.rmtree(a.out, ignore_errors=True)
    os.makedirs(a.out)
    r = Runner(os.path.abspath(a.radmesh), a.out, a.timeout)
    rnd = random.Random(62)
    work = os.path.join(a.out, "inputs")
    for group, fn in [("reader", lambda: reader_cases(r, rnd, work)), ("option", lambda: option_cases(r, work)),
                      ("physics", lambda: physics_cases(r, work)), ("output", lambda: output_cases(r, work)),
                      ("state", lambda: state_cases(r, rnd, work))]:
        if a.only in group:
            fn()
    with open(os.path.join(a.out, "cases.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["case", "category", "expect", "exit", "outcome", "detail"])
        w.writeheader()
        w.writerows(r.rows)
    counts = {}
    for row in r.rows:
        group = row["category"].split(":")[0]
        counts.setdefault(group, {})
        counts[group][row["outcome"]] = counts[group].get(row["outcome"], 0) + 1
    outcomes = ["right", "clear-error", "crash", "hang", "wrong", "leftover"]
    print("| group | runs | " + " | ".join(outcomes) + " |")
    print("|---|---|" + "---|" * len(outcomes))
    total = {o: 0 for o in outcomes}
    for group, c in counts.items():
        print("| %s | %d | " % (group, sum(c.values())) + " | ".join(str(c.get(o, 0)) for o in outcomes) + " |")
        for o in outcomes:
            total[o] += c.get(o, 0)
    print("| all | %d | " % len(r.rows) + " | ".join(str(total[o]) for o in outcomes) + " |")
    for row in r.rows:
        if row["outcome"] in ("crash", "hang", "wrong", "leftover"):
            print("%s: %s (%s): %s" % (row["outcome"], row["case"], row["category"], row["detail"]))
    sys.exit(1 if any(total[o] for o in ("crash", "hang", "wrong", "leftover")) else 0)


if __name__ == "__main__":
    main()
