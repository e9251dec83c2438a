#!/usr/bin/env python3
"""Writes the fuzzers' seed corpora (fuzz/corpus/<target>/) and the files the
JSON-scene target may name (fuzz/files/), from the bundled scenes, small
hand-made meshes and MGF files and, for the writers, fault points. Run from anywhere; the
output is committed."""
import base64
import json
import pathlib
import re
import shutil
import struct

here = pathlib.Path(__file__).resolve().parent
data = here.parent / "data"
corpus = here / "corpus"
files = here / "files"
MARK = b"\n#--MTL--\n"


def obj_with_mtl(obj_path):
    """The OBJ with its mtllib renamed to scene.mtl, the marker, then the MTL."""
    obj = obj_path.read_bytes()
    mtl_name = re.search(rb"^mtllib\s+(\S+)", obj, re.M).group(1).decode()
    mtl = (obj_path.parent / mtl_name).read_bytes()
    obj = re.sub(rb"^mtllib\s+\S+", b"mtllib scene.mtl", obj, flags=re.M)
    return obj.rstrip(b"\n") + MARK + mtl


# MGF seeds: every entity the reader knows, a face with a hole both ways,
# transforms with arrays and a mirror, the curved primitives, and the
# includes a single input can make (a missing file, itself).
MGF_SQUARE = b"v a =\n p 0 0 0\nv b =\n p 1 0 0\nv c =\n p 1 1 0\nv d =\n p 0 1 0\n"
MGF_LAMP = b"m lamp =\n c\n  cct 3000\n ed 1790\n sides 1\n"
MGF_SEEDS = {
    "holes": MGF_SQUARE + MGF_LAMP +
    b"v e =\n p .25 .25 0\nv f =\n p .75 .25 0\nv g =\n p .75 .75 0\nv h =\n p .25 .75 0\n"
    b"o wall\nf a b c d h g f e h d\no\nxf -t 0 0 1\nfh a b c d - e h g f\nxf\n",
    "primitives": b"v c =\n p 0 0 0\n n 0 0 1\nv t =\n p 0 0 2\n n 0 0 1\n" + MGF_LAMP +
    b"m paint =\n c\n  cspec 400 700 1 2 3 2 1\n rd .4\n rs .1 .05\n"
    b"sph c 3\ncyl c .5 t\ncone t .5 c -0\nring t .5 1\ntorus c .2 .4\nsph t -.1\n",
    "arrays": MGF_SQUARE + MGF_LAMP +
    b"c R =\n cxy .64 .33\nc B =\n cxy .15 .06\nm violet =\n c\n  cmix 1 R 1 B\n rd .1\n"
    b"o grid\nxf -t 2 0 0 -a 3 -t 0 2 0 -a 2 -t 0 0 5 -mz -rz 90\nprism a b c d .5\nxf\no\n"
    b"xf -s .5 -i 2 -t 0 0 3\nf a b c d\n",
    "includes": MGF_SQUARE + MGF_LAMP + b"f a b c d \\\n\n# comment \\\nf a b c\ni missing.mgf -t 1 0 0\n",
    "self_include": MGF_SQUARE + b"f a b c d\ni scene.mgf\n",
    "unknown_and_unused": MGF_SQUARE + MGF_LAMP + b"ts .1 .1\nir 1.5 0\ntd .1\nies lamp.ies -m 2\nfrob\nf a b c d\n",
}


def write(target, name, content):
    d = corpus / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(content)


# Small meshes: a tetrahedron in each assimp format.
P = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def ply_ascii():
    s = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    s += "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
    s += "".join("%g %g %g\n" % p for p in P) + "".join("3 %d %d %d\n" % f for f in F)
    return s.encode()


def ply_binary():
    h = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
         "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n").encode()
    return h + b"".join(struct.pack("<3f", *p) for p in P) + b"".join(struct.pack("<B3i", 3, *f) for f in F)


def normal(f):
    a, b, c = (P[i] for i in f)
    u = [b[k] - a[k] for k in range(3)]
    v = [c[k] - a[k] for k in range(3)]
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def stl_ascii():
    s = "solid tet\n"
    for f in F:
        s += " facet normal %g %g %g\n  outer loop\n" % normal(f)
        s += "".join("   vertex %g %g %g\n" % P[i] for i in f) + "  endloop\n endfacet\n"
    return (s + "endsolid tet\n").encode()


def stl_binary():
    out = b"tet".ljust(80, b" ") + struct.pack("<I", len(F))
    for f in F:
        out += struct.pack("<3f", *normal(f)) + b"".join(struct.pack("<3f", *P[i]) for i in f) + b"\0\0"
    return out


def off():
    return ("OFF\n4 4 6\n" + "".join("%g %g %g\n" % p for p in P) +
            "".join("3 %d %d %d\n" % f for f in F)).encode()


def gltf_parts(emissive):
    pos = b"".join(struct.pack("<3f", *p) for p in P)
    idx = b"".join(struct.pack("<3H", *f) for f in F)
    buf = pos + idx
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "translation": [0.5, 0, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.6, 0.7, 1]},
                       "emissiveFactor": emissive}],
        "buffers": [{"byteLength": len(buf)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                        {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 1]},
                      {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}],
    }
    return doc, buf


def gltf():
    doc, buf = gltf_parts([1, 1, 1])
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
    return json.dumps(doc).encode()


def glb():
    doc, buf = gltf_parts([0, 0, 0])
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    buf += b"\0" * (-len(buf) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(buf), 0x004E4942) + buf
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


# fuzz_numbers: a place, a byte (high bit: a run of zeros), then the token's
# characters as indices into the target's alphabet.
NUMBER_ALPHABET = "0123456789.eE+-0123456789.e-xXpPnNaAiIfFyY,0"
NUMBER_PLACES = ["obj_coordinate", "mtl_kd", "ply_float", "ply_double", "off_coordinate", "stl_coordinate",
                 "json_translate", "probe", "obj_index", "ply_index", "ply_count", "off_index"]


def number_seed(place, token, zeros=0):
    return bytes([NUMBER_PLACES.index(place), (0x80 | zeros) if zeros else 0]) + \
        bytes(NUMBER_ALPHABET.index(c) for c in token)


# fuzz_gltf_nodes: a shape (0 edges, 1 chain, 2 fan, 3 tree) and its bytes.
def nodes_seed(shape, *values):
    return bytes([shape, *values])


def gltf_with_nodes(nodes, roots):
    doc, buf = gltf_parts([1, 1, 1])
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
    doc["nodes"] = nodes
    doc["scenes"] = [{"nodes": roots}]
    return json.dumps(doc).encode()


def main():
    if corpus.exists():
        shutil.rmtree(corpus)
    if files.exists():
        shutil.rmtree(files)
    scenes = sorted(data.glob("*/*.obj"))
    for obj in scenes:
        write("fuzz_obj_reader", obj.stem, obj_with_mtl(obj))
        write("fuzz_mesh", obj.stem, obj_with_mtl(obj))
    # The stress scenes of issue 10, which crashed the mesher: two emitters,
    # and a floor vertex moved out of its plane.
    cornell = obj_with_mtl(data / "cornell_box" / "cornell_box.obj")
    write("fuzz_mesh", "cornell_two_emitters",
          cornell.replace(b"newmtl white\n", b"newmtl white\nKe 1 1 1\n")
                 .replace(b"newmtl red\n", b"newmtl red\nKe 1 1 1\n"))
    write("fuzz_mesh", "cornell_floor_vertex_moved", cornell.replace(b"v 552.8 0 0\n", b"v 552.8 300 0\n", 1))
    # A rug of 2 x 2 tiles lying in the floor's plane, each tile on its own
    # vertices: welded, then cut out of the floor together.
    obj, mtl = cornell.split(MARK)
    first = obj.count(b"\nv ") + 1
    rug = b"\no rug\nusemtl white\n"
    for i in range(2):
        for k in range(2):
            x, z = 50 + 50 * i, 350 + 50 * k
            rug += b"".join(b"v %d 0 %d\n" % p for p in [(x, z), (x, z + 50), (x + 50, z + 50), (x + 50, z)])
            n = first + 4 * (2 * i + k)
            rug += b"f %d %d %d %d\n" % (n, n + 1, n + 2, n + 3)
    write("fuzz_mesh", "cornell_tiled_rug", obj.rstrip(b"\n") + rug + MARK + mtl)
    # Narrow gaps: a panel standing 1e-5 from the floor's edge (the mesher
    # must not cut the edge about the gap apart), and a panel standing 1e-10
    # from the edge of a thin strip lying in the floor (which can crash CGAL's
    # mesher).
    lamp = b"newmtl lamp\nKd 0.5 0.5 0.5\nKe 1 1 1\n"
    write("fuzz_mesh", "narrow_gap_panel",
          b"mtllib scene.mtl\nusemtl lamp\nv 0 0 0\nv 0 0 4\nv 4 0 4\nv 4 0 0\n"
          b"v 1e-5 0 1.5\nv 1e-5 1 1.5\nv 1e-5 1 2.5\nv 1e-5 0 2.5\no floor\nf 1 2 3 4\no panel\nf 5 6 7 8" + MARK + lamp)
    write("fuzz_mesh", "thin_strip_vertex",
          b"mtllib scene.mtl\nusemtl lamp\nv 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 0.5 0.5 0\nv 1.5 0.5 0\n"
          b"v 1 0.50000001 0\nv 1 0.5000000001 0\nv 1.2 0.5000000001 1\nv 1 0.5000000001 1\n"
          b"o floor\nf 1 2 3 4\no strip\nf 5 6 7\no panel\nf 8 9 10" + MARK + lamp)
    # A rug 1 mm above a floor and a tilted one over it (overhang lines, cut
    # along their projected outlines), and a slab 1 mm thick lying on it.
    write("fuzz_mesh", "rug_overhang",
          b"mtllib scene.mtl\nusemtl lamp\nv 0 0 0\nv 0 0 4\nv 4 0 4\nv 4 0 0\n"
          b"v 1 0.001 1\nv 1 0.001 3\nv 3 0.001 3\nv 3 0.001 1\n"
          b"v 1.5 0.002 1.5\nv 1.5 0.002 2.5\nv 2.5 0.0021 2.5\nv 2.5 0.0021 1.5\n"
          b"v 0.2 0 0.2\nv 0.8 0 0.2\nv 0.8 0.001 0.2\nv 0.2 0.001 0.2\n"
          b"o floor\nf 1 2 3 4\no rug\nf 5 6 7 8\no tilted\nf 9 10 11 12\no slab_side\nf 13 14 15 16" + MARK + lamp)

    formats = [(0, "ply_ascii", ply_ascii()), (0, "ply_binary", ply_binary()), (1, "stl_ascii", stl_ascii()),
               (1, "stl_binary", stl_binary()), (2, "off", off()), (3, "gltf", gltf()), (4, "glb", glb())]
    for selector, name, content in formats:
        write("fuzz_assimp_reader", name, bytes([selector]) + content)

    write("fuzz_mgf_reader", "cornell_box", (data / "cornell_box" / "cornell_box.mgf").read_bytes())
    for name, content in MGF_SEEDS.items():
        write("fuzz_mgf_reader", name, content)

    # Hostile files of the reader classes (docs/scenes.md, "File checks"):
    # node trees deep, wide and cyclic; data past the declared counts;
    # strides that overlap; a GLB with bytes past its declared length.
    chain = [{"children": [i + 1]} for i in range(299)] + [{"mesh": 0}]
    hostile = [(3, "gltf_chain_300_levels", gltf_with_nodes(chain, [0])),
               (3, "gltf_fan_2000", gltf_with_nodes([{"mesh": 0, "children": list(range(1, 2000))}] +
                                                     [{} for _ in range(1999)], [0])),
               (3, "gltf_cycle", gltf_with_nodes([{"children": [1]}, {"mesh": 0, "children": [0]}], [0])),
               (3, "gltf_two_parents", gltf_with_nodes([{"children": [2]}, {"children": [2]}, {"mesh": 0}], [0, 1])),
               (2, "off_extra_face", off() + b"3 0 1 2\n"),
               (2, "off_hex_coordinate", off().replace(b"\n1 0 0\n", b"\n0x1p0 0 0\n")),
               (0, "ply_ascii_extra_value", ply_ascii().replace(b"\n1 0 0\n", b"\n1 0 0 5\n")),
               (0, "ply_ascii_long_digits", ply_ascii().replace(b"\n1 0 0\n", b"\n123456789012345678901234e-23 0 0\n")),
               (1, "stl_ascii_extra_value", stl_ascii().replace(b"vertex 1 0 0\n", b"vertex 1 0 0 7\n", 1))]
    doc, buf = gltf_parts([1, 1, 1])
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
    doc["bufferViews"][0]["byteStride"] = 4
    hostile.append((3, "gltf_stride_4", json.dumps(doc).encode()))
    hostile.append((4, "glb_tail", glb() + b"junk"))
    for selector, name, content in hostile:
        write("fuzz_assimp_reader", name, bytes([selector]) + content)
    bom = obj_with_mtl(data / "parallel_plates" / "parallel_plates.obj")
    write("fuzz_obj_reader", "bom_and_hex", b"\xef\xbb\xbf" + bom.replace(b"\nv ", b"\nv 0x1p0 ", 1))
    write("fuzz_json_scene", "nul_in_file_name", b'{"objects": [{"file": "room.obj\\u0000.ply"}]}')

    for place, token, zeros in [("obj_coordinate", "1.5", 0), ("obj_coordinate", "0x1p0", 0),
                                ("obj_coordinate", "0.1e1", 90), ("mtl_kd", "0.5", 0), ("mtl_kd", "+0.5", 0),
                                ("ply_float", "123456789012345678901234e-23", 0), ("ply_float", "1,5", 0),
                                ("ply_double", "0.0000000000000000015e18", 0), ("off_coordinate", "15e-1", 0),
                                ("off_coordinate", "1e99999999999999999999", 0), ("stl_coordinate", "-.5E+1", 0),
                                ("stl_coordinate", "nan", 0), ("json_translate", "1.25", 0),
                                ("json_translate", "-0.0e-400", 0), ("probe", "2.5", 0), ("probe", "inf", 0),
                                ("obj_index", "-1", 0), ("obj_index", "+3", 0), ("ply_index", "002", 0),
                                ("ply_index", "4294967298", 0), ("ply_count", "3", 0), ("off_index", "-1", 0)]:
        write("fuzz_numbers", "%s_%s" % (place, re.sub(r"[^0-9a-zA-Z]", "_", token)), number_seed(place, token, zeros))

    for name, content in [("explicit_tree", nodes_seed(0, 5, 0, 1, 4, 0, 2, 4, 1, 3, 5, 2, 4, 9)),
                          ("explicit_cycle", nodes_seed(0, 3, 0, 1, 5, 1, 2, 4, 2, 0, 4)),
                          ("explicit_two_parents", nodes_seed(0, 3, 0, 2, 5, 1, 2, 7)),
                          ("explicit_fraction", nodes_seed(0, 2, 0, 1, 0xF5)),
                          ("chain_200", nodes_seed(1, 200, 0, 0)),
                          ("chain_300", nodes_seed(1, 44, 1, 0)),
                          ("chain_cycle", nodes_seed(1, 10, 0, 1, 3)),
                          ("fan_500", nodes_seed(2, 0xF4, 1, 2)),
                          ("fan_past_the_bound", nodes_seed(2, 3, 0, 0xFF)),
                          ("tree_3_ary", nodes_seed(3, 2, 6))]:
        write("fuzz_gltf_nodes", name, content)

    # The writers: byte 0 the groups of files (0: all), byte 1 the fault
    # (0: the disk fills, 1: a rename fails), then where, as a fraction of
    # 2^32 of the set's bytes (renames); 2^32 - 1: no fault.
    for fault, kind in ((0, "full"), (1, "rename")):
        for frac in (0.0, 0.1, 0.5, 0.9, 0.999):
            write("fuzz_writers", "all_%s_%03d" % (kind, round(1000 * frac)),
                  bytes([0, fault]) + struct.pack("<I", int(frac * 2 ** 32)))
    write("fuzz_writers", "all_no_fault", bytes([0, 0]) + struct.pack("<I", 2 ** 32 - 1))
    for groups, name in ((1, "vtk"), (2, "pixmap"), (4, "tables")):
        write("fuzz_writers", name + "_full_500", bytes([groups, 0]) + struct.pack("<I", 2 ** 31))

    files.mkdir(parents=True)
    (files / "room.obj").write_bytes((data / "bunny" / "room.obj").read_bytes())
    (files / "room.mtl").write_bytes((data / "bunny" / "room.mtl").read_bytes())
    (files / "tet.ply").write_bytes(ply_ascii())
    (files / "tet.stl").write_bytes(stl_binary())
    (files / "tet.off").write_bytes(off())
    (files / "tet.gltf").write_bytes(gltf())
    (files / "tiles.mgf").write_bytes(MGF_SEEDS["arrays"])
    write("fuzz_json_scene", "room_and_tet", json.dumps({
        "materials": {"clay": {"reflectance": [0.6, 0.5, 0.4]}},
        "objects": [{"file": "room.obj"},
                    {"file": "tet.ply", "material": "clay",
                     "transform": {"scale": 0.2, "rotate_deg": [0, 90, 0], "translate": [0.5, 0, 0.5]}}]},
        indent=1).encode())
    write("fuzz_json_scene", "every_format", json.dumps({
        "materials": {"grey": {"reflectance": [0.5, 0.5, 0.5]},
                      "lamp": {"reflectance": [0, 0, 0], "emission": [10, 10, 10]}},
        "objects": [{"file": "tet.stl", "material": "lamp", "transform": {"scale": [1, 2, -1]}},
                    {"file": "tet.off", "material": "grey", "transform": {"translate": [3, 0, 0]}},
                    {"file": "tet.gltf", "transform": {"translate": [0, 3, 0]}},
                    {"file": "tiles.mgf", "transform": {"translate": [0, 0, 10]}}]}, indent=1).encode())


main()
