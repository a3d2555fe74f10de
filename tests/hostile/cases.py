"""Hostile inputs, generated at test time (no stored bombs): each case is a `jax3dc` command line
that must fail with exit 1 and one line on stderr naming the problem.

``build_cases(root)`` writes the input files under ``root / "in"`` and returns the cases; every
command writes (if at all) under ``root / "out" / <case>``.
"""

from __future__ import annotations

import json
import os
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Case:
    """One hostile command: ``kind`` groups cases in the report; ``expect`` must appear in the error line."""

    kind: str
    name: str
    argv: tuple[str, ...]
    expect: str


_BOX_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n" \
           "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n"


def _programs() -> dict[str, tuple[str, str]]:
    """name -> (program text, words expected in the error)."""
    big = "a = sphere(1, segments=256, rings=128)\n"
    # a lattice of 972 crossing rods cut from a fine sphere: 10-20 s of booleans on one core,
    # so the budget must stop it inside difference()
    rods = []
    for i in range(18):
        for j in range(18):
            a, b = i / 18 - 0.45, j / 18 - 0.45
            rods += [f"box((2, 0.02, 0.02), center=(0, {a}, {b}))", f"box((0.02, 2, 0.02), center=({a}, 0, {b}))",
                     f"box((0.02, 0.02, 2), center=({a}, {b}, 0))"]
    cutters = ", ".join(rods)
    return {
        "emit_many": (big + "for i in range(1, 5001):\n    part(i, 'c', a)\n", "triangle budget"),
        "emit_combine": (big + "b = combine(" + ", ".join(["a"] * 300) + ")\npart(1, 'b', b)\n", "triangle budget"),
        "array_bomb": (big + "b = linear_array(a, 1000, (1, 0, 0))\n", "triangle budget"),
        "grid_bomb": (big + "b = grid_array(a, (10, 10, 10))\n", "triangle budget"),
        "long_boolean": ("a = difference(sphere(0.7, segments=256, rings=128), " + cutters + ")\npart(1, 'a', a)\n", "time budget"),
        "operands": ("a = box(1)\nb = combine(" + ", ".join(["a"] * 30000) + ")\n", "at most 1000"),
        "segments": ("part(1, 'a', cylinder(0.5, 1, segments=10000))\n", "segments"),
        "nested_loops": ("for i in range(10000):\n    for j in range(10000):\n        b = j\n", "step budget"),
        "range_huge": ("for i in range(" + "9" * 40 + "):\n    b = i\n", "too large"),
        "int_literal": ("a = box(" + "9" * 400 + ")\n", "too large"),
        "int_division": ("a = " + "9" * 15 + " * " + "9" * 15 + "\n", "too large"),
        "float_inf": ("a = box(1e999)\n", "finite"),
        "float_overflow": ("a = box(1e308 * 10)\n", "finite"),
        "center_huge": ("a = box(1, center=(1e300, 0, 0))\n", "finite"),
        "scale_runaway": ("a = box(1)\n" + "a = scale(a, 1000000)\n" * 4 + "part(1, 'a', a)\n", "coordinates"),
        "deep_parens": ("a = " + "(" * 5000 + "1" + ")" * 5000 + "\n", "nested"),
        "long_chain": ("a = " + "+".join(["1"] * 200_000) + "\n", "nested too deeply"),
        "unary_chain": ("a = " + "-" * 200_000 + "1\n", "nested too deeply"),
        "import": ("import os\n", "imports are not allowed"),
        "dunder": ("a = box.__class__\n", "attribute"),
        "dunder_name": ("__builtins__ = 1\n", "dunder"),
        "exec_call": ("exec('print(1)')\n", "not a predefined function"),
        "open_call": ("a = open('/etc/passwd')\n", "not a predefined function"),
        "lambda": ("a = lambda: 1\n", "lambda"),
        "while": ("while 1:\n    pass\n", "while"),
        "power": ("a = 9 ** 9 ** 9\n", "only + - * /"),
        "comprehension": ("a = [box(1) for i in range(10**6)]\n", "comprehension"),
        "surrogate": ("part(1, '\\ud800', box())\n", "lone surrogate"),
        "twice": ("part(1, 'a', box())\npart(1, 'b', box())\n", "named twice"),
        "no_part": ("a = box(1)\n", "names no part"),
        "nul_byte": ("a = box(1)\x00\n", "program"),
        "syntax": ("part(1, 'a', box(\n", "syntax error"),
        "bool_literal": ("a = box(True)\n", "literal"),
        "long_name": ("a = " + "x" * 100_000 + "\n", "unknown name"),
        "big_string": ("part(1, '" + "x" * 900_000 + "', box())\npart(1, 'b', box())\n", "named twice"),
    }


def _program_cases(inputs: Path, out: Path) -> list[Case]:
    cases = []
    folder = inputs / "programs"
    folder.mkdir()
    for name, (text, expect) in _programs().items():
        path = folder / f"{name}.py"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        # the boolean alone takes 10 s or more: a tight budget keeps the case short
        budget = ("--max-seconds", "0.1" if name == "long_boolean" else "2")
        cases.append(Case("program run", name, ("program", "run", str(path), "--out", str(out / f"run_{name}"),
                                                *budget), expect))
        cases.append(Case("program blender", name, ("program", "blender", str(path), "-o",
                                                    str(out / f"blender_{name}" / "s.py"), *budget), expect))
    (folder / "latin1.py").write_bytes(b"part(1, '\xe9', box())\n")
    (folder / "huge.py").write_bytes(b"#" * (4_000_001 + 16))
    (folder / "ok.py").write_text("part(1, 'a', box())\n")
    cases += [
        Case("program run", "not_utf8", ("program", "run", str(folder / "latin1.py")), "cannot read the program"),
        Case("program run", "huge_file", ("program", "run", str(folder / "huge.py")), "bytes"),
        Case("program run", "missing", ("program", "run", str(folder / "absent.py")), "absent.py"),
        Case("program run", "directory", ("program", "run", str(folder)), "programs"),
        Case("program blender", "missing_out_folder",
             ("program", "blender", str(folder / "ok.py"), "-o", str(out / "no" / "such" / "s.py")), "No such file"),
        Case("program run", "out_is_file", ("program", "run", str(folder / "ok.py"), "--out", str(folder / "ok.py")),
             "cannot write"),
    ]
    return cases


def _structure(desc: str = '"oak"', node_extra: str = "") -> str:
    """A root (1) and its child (2); ``node_extra`` is added to the child."""
    return ('{"materials":{"0":{"family":"Wood","desc":' + desc + '}},"nodes":{"1":{"parent":null,"material":0},'
            '"2":{"parent":1,"material":0' + node_extra + '}},"relations":[]}')


def _documents() -> dict[str, tuple[bytes, str]]:
    chain = ",".join(f'"{i}":{{"parent":{i - 1},"material":0}}' for i in range(2, 1001))
    cycle = '{"materials":{"0":{"family":"Wood"}},"nodes":{"1":{"parent":2,"material":0},' \
            '"2":{"parent":1,"material":0}},"relations":[]}'
    return {
        "deep_array": (b"[" * 100_000 + b"]" * 100_000, "nested too deeply"),
        "deep_object": (b'{"a":' * 100_000 + b"1" + b"}" * 100_000, "nested too deeply"),
        "deep_in_desc": (_structure("[" * 50_000 + "]" * 50_000).encode(), "nested too deeply"),
        "surrogate_desc": (_structure('"\\ud800"').encode(), "lone surrogate"),
        "surrogate_low": (_structure('"a\\udfff"').encode(), "lone surrogate"),
        "surrogate_name": (_structure(node_extra=',"name":"\\udc80"').encode(), "lone surrogate"),
        "surrogate_key": (_structure().replace('"desc"', '"\\ud800"').encode(), "unknown key"),
        "nan": (_structure(node_extra=',"joint":{"type":"hinge","axis":[NaN,0,1],"pivot":[0,0,0],"range":[0,1]}')
                .encode(), "not finite"),
        "inf_pivot": (_structure(node_extra=',"joint":{"type":"hinge","axis":[0,0,1],"pivot":[1e400,0,0],'
                                            '"range":[0,1]}').encode(), "not finite"),
        "huge_int": (_structure(node_extra=',"joint":{"type":"hinge","axis":[' + "9" * 5000 + ',0,1],'
                                           '"pivot":[0,0,0],"range":[0,1]}').encode(), "invalid JSON"),
        "big_number": (_structure(node_extra=',"joint":{"type":"slide","axis":[1e308,1e308,1e308],'
                                             '"pivot":[-1e308,0,0],"range":[0,1]}').encode(), "joint"),
        "duplicate": (_structure().replace('"relations":[]', '"relations":[],"relations":[]').encode(),
                      "appears twice"),
        "too_big": (b'{"pad":"' + b"x" * (2 << 20) + b'"}', "limit"),
        "not_utf8": (b'{"materials":{"0":{"family":"Wood","desc":"\xff\xfe"}}}', "not UTF-8"),
        "empty": (b"", "invalid JSON"),
        "truncated": (_structure().encode()[:40], "truncated"),
        "top_list": (b"[1,2,3]", "object"),
        "cycle": (cycle.encode(), "cycle"),
        "chain_cycle": (('{"materials":{"0":{"family":"Wood"}},"nodes":{"1":{"parent":1000,"material":0},'
                         + chain + '},"relations":[]}').encode(), "cycle"),
        "bad_family": (_structure().replace("Wood", "Unobtainium").encode(), "family"),
        "bad_id": (_structure().replace('"2":{', '"02":{').encode(), "id"),
        "huge_id": (_structure().replace('"2":{', '"' + "9" * 40 + '":{').encode(), "id"),
        "nul": (b'{"materials":\x00}', "invalid JSON"),
    }


def _structure_cases(inputs: Path, out: Path) -> list[Case]:
    folder = inputs / "structures"
    folder.mkdir()
    boxes = folder / "boxes.json"
    boxes.write_text('{"1":{"centroid":[0,0,0],"extent":[1,1,1]},"2":{"centroid":[0,0,0],"extent":[1,1,1]}}')
    cases = []
    for name, (data, expect) in _documents().items():
        path = folder / f"{name}.json"
        path.write_bytes(data)
        cases.append(Case("structure validate", name, ("validate", str(path)), expect))
        cases.append(Case("structure canonicalize", name, ("canonicalize", str(path), "--boxes", str(boxes),
                                                           "--out", str(out / f"canon_{name}.json")), expect))
    good = folder / "good.json"
    good.write_text(_structure())
    bad_boxes = {
        "boxes_deep": (b"[" * 100_000, "nested too deeply"),
        "boxes_nan": (b'{"1":{"centroid":[NaN,0,0],"extent":[1,1,1]}}', "finite"),
        "boxes_huge": (b'{"pad":"' + b"x" * (5 << 20) + b'"}', "bytes"),
        "boxes_int": (b'{"1":{"centroid":[' + b"9" * 5000 + b',0,0],"extent":[1,1,1]}}', "invalid JSON"),
        "boxes_surrogate": (b'{"\\ud800":{}}', "box"),
    }
    for name, (data, expect) in bad_boxes.items():
        path = folder / f"{name}.json"
        path.write_bytes(data)
        cases.append(Case("structure canonicalize", name, ("canonicalize", str(good), "--boxes", str(path)), expect))
    long_path = str(folder / ("x" * 100_000))
    cases += [
        Case("structure validate", "parts_20M", ("validate", str(good), "--parts", "20000000"), "--max-parts"),
        Case("structure validate", "long_path", ("validate", long_path), "characters cut"),
        Case("structure validate", "missing", ("validate", str(folder / "absent.json")), "no such file"),
        Case("structure validate", "directory", ("validate", str(folder)), "directory"),
        Case("structure canonicalize", "missing_out_folder",
             ("canonicalize", str(good), "--boxes", str(boxes), "--out", str(out / "no" / "such" / "c.json")),
             "cannot write"),
        Case("structure canonicalize", "long_boxes_path", ("canonicalize", str(good), "--boxes", long_path),
             "characters cut"),
    ]
    return cases


def _urdf(mesh: str = "", body: str = "") -> str:
    visual = f'<visual><geometry><mesh filename="{mesh}"/></geometry></visual>' if mesh else ""
    return f'<?xml version="1.0"?><robot name="r"><link name="a">{visual}{body}</link></robot>'


def _mjcf(asset: str = "", world: str = "") -> str:
    return f"<mujoco><asset>{asset}</asset><worldbody>{world}</worldbody></mujoco>"


def _import_files(outside: Path) -> dict[str, tuple[dict[str, bytes | str], str]]:
    """name -> ({relative path: content, or "->target" for a symbolic link}, words expected)."""
    box = _BOX_OBJ
    mesh_geom = '<body name="b"><geom type="mesh" mesh="m"/></body>'
    many_faces = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n" + "f 1 2 3\n" * 2_100_000
    stl_lie = b"\0" * 80 + struct.pack("<I", 50_000_000)
    ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n" \
          "element face 90000000\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
    replicate = '<replicate count="1000">' * 3 + '<body><geom size="0.1"/></body>' + "</replicate>" * 3
    geoms = '<body><replicate count="100000"><geom size="0.1"/></replicate></body>'
    laughs = '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">' \
             '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;">]><robot name="&c;"><link name="a"/></robot>'
    external = '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY e SYSTEM "file:///etc/passwd">]><robot name="&e;"/>'
    deep = "<robot name='r'>" + "<link name='a'>" + "<x>" * 100_000 + "</x>" * 100_000 + "</link></robot>"
    links = "".join(f'<link name="l{i}"/>' for i in range(10_001))
    prim = "".join(f'<visual><geometry><sphere radius="{1 + i}"/></geometry></visual>' for i in range(7000))
    return {
        "urdf_dotdot": ({"robot.urdf": _urdf("../outside.obj")}, "--allow-outside"),
        "urdf_dotdot_deep": ({"robot.urdf": _urdf("m/../../../outside.obj")}, "--allow-outside"),
        "urdf_absolute": ({"robot.urdf": _urdf(str(outside))}, "--allow-outside"),
        "urdf_file_url": ({"robot.urdf": _urdf("file://" + str(outside))}, "--allow-outside"),
        "urdf_package": ({"robot.urdf": _urdf("package://x/../outside.obj")}, "package 'x' not found"),
        "urdf_package_escape": ({"package.xml": "<package><name>x</name></package>",
                                 "robot.urdf": _urdf("package://x/../outside.obj")}, "leaves package 'x'"),
        "urdf_symlink": ({"robot.urdf": _urdf("m/link.obj"), "m/link.obj": "->" + str(outside)}, "--allow-outside"),
        "urdf_symlink_dir": ({"robot.urdf": _urdf("up/outside.obj"), "up": "->" + str(outside.parent)},
                             "--allow-outside"),
        "urdf_etc_passwd": ({"robot.urdf": _urdf("m/p.obj"), "m/p.obj": "->/etc/passwd"}, "--allow-outside"),
        "urdf_many_faces": ({"robot.urdf": _urdf("big.obj"), "big.obj": many_faces}, "--max-faces"),
        "urdf_stl_header": ({"robot.urdf": _urdf("lie.stl"), "lie.stl": stl_lie}, "geometry"),
        "urdf_ply_header": ({"robot.urdf": _urdf("lie.ply"), "lie.ply": ply}, "--max-faces"),
        "urdf_primitives": ({"robot.urdf": _urdf(body=prim)}, "--max-faces"),
        "urdf_links": ({"robot.urdf": f'<robot name="r">{links}</robot>'}, "--max-bodies"),
        "urdf_huge_vertices": ({"robot.urdf": _urdf("h.obj"), "h.obj": box.replace("v 1", "v 1e308")}, "beyond"),
        "urdf_nan_vertices": ({"robot.urdf": _urdf("n.obj"), "n.obj": box.replace("v 1 ", "v nan ")}, "finite"),
        "urdf_huge_box": ({"robot.urdf": _urdf(body='<visual><geometry><box size="1e308 1e308 1e308"/></geometry>'
                                                    '</visual>')}, "beyond"),
        "urdf_huge_origin": ({"robot.urdf": '<robot name="r"><link name="a"><visual><origin xyz="1e308 0 0"/>'
                                            '<geometry><box size="1 1 1"/></geometry></visual></link>'
                                            '<link name="b"><visual><origin xyz="-1e308 0 0"/><geometry>'
                                            '<box size="1 1 1"/></geometry></visual></link><joint name="j" '
                                            'type="fixed"><parent link="a"/><child link="b"/></joint></robot>'},
                             "extent"),
        "urdf_empty_only": ({"robot.urdf": _urdf("e.obj"), "e.obj": b""}, "no geometry left"),
        "urdf_missing_mesh": ({"robot.urdf": _urdf("gone.obj")}, "not found"),
        "urdf_mesh_is_dir": ({"robot.urdf": _urdf("d.obj"), "d.obj/x": b""}, "not found"),
        "urdf_laughs": ({"robot.urdf": laughs}, "DOCTYPE"),
        "urdf_external": ({"robot.urdf": external}, "DOCTYPE"),
        "urdf_deep_xml": ({"robot.urdf": deep}, "no link has any geometry"),
        "urdf_meta_deep": ({"mobility.urdf": _urdf("../outside.obj"), "meta.json": "[" * 100_000}, "--allow-outside"),
        "urdf_malformed": ({"robot.urdf": "<robot><link></robot>"}, "malformed XML"),
        "mjcf_dotdot": ({"m.xml": _mjcf('<mesh name="m" file="../outside.obj"/>', mesh_geom)}, "--allow-outside"),
        "mjcf_absolute": ({"m.xml": _mjcf(f'<mesh name="m" file="{outside}"/>', mesh_geom)}, "--allow-outside"),
        "mjcf_meshdir": ({"m.xml": '<mujoco><compiler meshdir=".."/>' + _mjcf('<mesh name="m" file="outside.obj"/>',
                                                                               mesh_geom)[8:]}, "--allow-outside"),
        "mjcf_symlink": ({"m.xml": _mjcf('<mesh name="m" file="l.obj"/>', mesh_geom), "l.obj": "->" + str(outside)},
                         "--allow-outside"),
        "mjcf_include": ({"m.xml": '<mujoco><include file="../x.xml"/></mujoco>'}, "--allow-outside"),
        "mjcf_replicate": ({"m.xml": _mjcf(world=replicate)}, "--max-bodies"),
        "mjcf_replicate_geoms": ({"m.xml": _mjcf(world=geoms)}, "--max-bodies"),
        "mjcf_hfield": ({"m.xml": _mjcf('<hfield name="h" nrow="100000" ncol="100000" size="1 1 1 1"/>',
                                        '<geom type="hfield" hfield="h"/>')}, "--max-faces"),
        "mjcf_many_faces": ({"m.xml": _mjcf('<mesh name="m" file="big.obj"/>', mesh_geom), "big.obj": many_faces},
                            "--max-faces"),
        "mjcf_laughs": ({"m.xml": laughs.replace("robot", "mujoco")}, "DOCTYPE"),
        "mjcf_bad_mesh": ({"m.xml": _mjcf('<mesh name="m" file="t.obj"/>', mesh_geom), "t.obj": "v 0 0 0\nf 1 1 1\n"},
                          "MuJoCo"),
    }


def _import_cases(inputs: Path, out: Path) -> list[Case]:
    outside = inputs / "outside.obj"
    outside.write_text(_BOX_OBJ)
    cases = []
    for name, (files, expect) in _import_files(outside).items():
        folder = inputs / "objects" / name
        for relative, content in files.items():
            path = folder / relative
            path.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, str) and content.startswith("->"):
                os.symlink(content[2:], path)
            elif isinstance(content, bytes):
                path.write_bytes(content)
            else:
                path.write_text(content)
        cases.append(Case("data convert", name, ("data", "convert", str(folder), "--out", str(out / name), "--quiet"),
                          expect))
    return cases


def _chain(depth: int) -> str:
    """A structure whose parent chain is ``depth`` parts long, a hinge on every child."""
    joint = '"joint":{"type":"hinge","axis":[0,0,1],"pivot":[0,0,0],"range":[0,0.1]}'
    nodes = ['"1":{"parent":null,"material":0}'] + [f'"{i}":{{"parent":{i - 1},"material":0,{joint}}}'
                                                   for i in range(2, depth + 1)]
    return '{"materials":{"0":{"family":"Wood"}},"nodes":{' + ",".join(nodes) + '},"relations":[]}'


def _object_cases(inputs: Path, out: Path) -> list[Case]:
    """A structure with its parts through `export` (every format) and `physics check`."""
    folder = inputs / "objects_with_parts"
    deep_parts, far_parts = folder / "deep_parts", folder / "far_parts"
    deep_parts.mkdir(parents=True)
    far_parts.mkdir()
    cube = "v 0 0 0\nv .01 0 0\nv 0 .01 0\nv 0 0 .01\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    for i in range(1, 1001):
        (deep_parts / f"{i}.obj").write_text(cube)
    (far_parts / "1.obj").write_text(_BOX_OBJ)
    (far_parts / "2.obj").write_text("v 1e308 0 0\nv 0 1e308 0\nv 0 0 1e308\nv -1e308 -1e308 -1e308\n"
                                     "f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
    many_parts = folder / "many_faces"  # under the per-file cap, over the physics check's per-object one
    many_parts.mkdir()
    (many_parts / "1.obj").write_text(_BOX_OBJ)
    (many_parts / "2.obj").write_text("v 0 0 2\nv 1 0 2\nv 0 1 2\nv 0 0 3\n" + "f 1 2 3\n" * 310_000)
    deep, pair = _write(folder / "deep.json", _chain(1000)), _write(folder / "pair.json", _chain(2))
    inputs_by_name = {"chain_1000": (deep, deep_parts, "more than 400 parts deep"),
                      "far_vertices": (pair, far_parts, "beyond")}
    cases = []
    for name, (structure, parts, expect) in inputs_by_name.items():
        if name != "chain_1000":  # every format but MJCF nests nothing, and takes a deep chain
            for fmt in ("urdf", "usd", "gltf", "blender"):
                cases.append(Case("export", f"{name}_{fmt}", ("export", str(structure), "--parts", str(parts), "--format",
                                                             fmt, "--out", str(out / f"export_{name}_{fmt}")), expect))
        cases.append(Case("export", f"{name}_mjcf", ("export", str(structure), "--parts", str(parts), "--format", "mjcf",
                                                    "--out", str(out / f"export_{name}_mjcf")), expect))
        cases.append(Case("physics check", name, ("physics", "check", str(structure), "--parts", str(parts)), expect))
    cases.append(Case("physics check", "object_faces", ("physics", "check", str(pair), "--parts", str(many_parts)),
                      "--max-faces"))
    cases.append(Case("export", "object_faces_mjcf", ("export", str(pair), "--parts", str(many_parts), "--format", "mjcf",
                                                      "--out", str(out / "export_object_faces")), "--max-faces"))
    cases.append(Case("physics check", "part_faces", ("physics", "check", str(pair), "--parts", str(many_parts),
                                                      "--max-part-faces", "1000"), "--max-part-faces"))
    for name, (text, expect) in _exported_mjcf_files().items():  # physics check reads an exported object.xml
        cases.append(Case("physics check", f"mjcf_{name}", ("physics", "check", str(_write(folder / f"{name}.xml", text))),
                          expect))
    return cases


def _exported_mjcf_files() -> dict[str, tuple[str, str]]:
    """name -> (an object.xml given to physics check, words expected in the error)."""
    laughs = ('<?xml version="1.0"?><!DOCTYPE m [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">'
              '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;">]><mujoco><custom><text name="jax3dc_structure" data="&c;"/>'
              '</custom></mujoco>')
    cycle = ('{&quot;materials&quot;:{&quot;0&quot;:{&quot;family&quot;:&quot;Wood&quot;}},&quot;nodes&quot;:{'
             '&quot;1&quot;:{&quot;parent&quot;:2,&quot;material&quot;:0},&quot;2&quot;:{&quot;parent&quot;:1,'
             '&quot;material&quot;:0}},&quot;relations&quot;:[]}')
    texts = '<text name="jax3dc_scale" data="{}"/><text name="jax3dc_mounted" data="false"/>'
    return {
        "entities": (laughs, "DTD"),
        "not_xml": ("<mujoco><worldbody>", "not readable XML"),
        "foreign": ('<mujoco><worldbody><body><geom type="box" size=".1 .1 .1"/></body></worldbody></mujoco>',
                    "not a file written by jax3dc export"),
        "cyclic_structure": (f'<mujoco><custom><text name="jax3dc_structure" data="{cycle}"/>{texts.format(1.0)}'
                             '</custom><worldbody/></mujoco>', "cycle"),
        "negative_scale": (f'<mujoco><custom><text name="jax3dc_structure" data="{cycle.replace("2,", "null,", 1)}"/>'
                           f'{texts.format(-1.0)}</custom><worldbody/></mujoco>', "positive number"),
    }


def _metric_line(key: str = '"a"', structure: str | None = None, boxes: str | None = None) -> str:
    """A reference line for the two-part structure of ``_structure``."""
    box = '{"centroid":[0,0,0],"extent":[1,1,1]}'
    return ('{"key":' + key + ',"structure":' + (structure or _structure()) + ',"boxes":'
            + (boxes or '{"1":' + box + ',"2":' + box + '}') + "}\n")


def _metric_files() -> dict[str, tuple[bytes, str]]:
    """name -> (JSONL content, words expected); each is tried as --ref and as --pred."""
    return {
        "bad_json": (b'{"key":"a",\n', "not JSON"),
        "deep": (b'{"key":"a","structure":' + b"[" * 100_000 + b"]" * 100_000 + b"}\n", "nested too deeply"),
        "huge_int": (_metric_line(boxes='{"1":{"centroid":[' + "9" * 5000 + ',0,0],"extent":[1,1,1]}}').encode(),
                     "4300 digits"),
        "nan": (b'{"key":"a","score":NaN}\n', "NaN"),
        "infinity": (_metric_line(boxes='{"1":{"centroid":[0,-Infinity,0],"extent":[1,1,1]}}').encode(), "Infinity"),
        "surrogate_key": (_metric_line(key='"\\ud800"').encode(), "lone surrogate"),
        "missing_key": (b'{"structure":{},"boxes":{}}\n', '"key"'),
        "key_not_string": (_metric_line(key="7").encode(), '"key"'),
        "top_list": (b"[1,2,3]\n", '"key"'),
        "duplicate_member": (_metric_line().replace('"key":"a"', '"key":"a","key":"b"').encode(), "appears twice"),
        "duplicate_line": (_metric_line().encode() * 2, "duplicate key"),
        "long_line": (b'{"key":"a","text":"' + b"x" * (40 << 20) + b'"}\n', "bytes"),
        "not_utf8": (b'{"key":"\xff\xfe"}\n', "not UTF-8"),
    }


def _metric_cases(inputs: Path, out: Path) -> list[Case]:
    folder = inputs / "metrics"
    folder.mkdir()
    good_ref, good_pred = folder / "ref.jsonl", folder / "pred.jsonl"
    good_ref.write_text(_metric_line())
    good_pred.write_text('{"key":"a","text":' + json.dumps(_structure()) + "}\n")
    cases = []
    for name, (data, expect) in _metric_files().items():
        path = folder / f"{name}.jsonl"
        path.write_bytes(data)
        cases.append(Case("eval metrics", f"ref_{name}", ("eval", "metrics", "--ref", str(path), "--pred",
                                                           str(good_pred), "--out", str(out / f"ref_{name}")), expect))
        cases.append(Case("eval metrics", f"pred_{name}", ("eval", "metrics", "--ref", str(good_ref), "--pred",
                                                            str(path), "--out", str(out / f"pred_{name}")), expect))
    refs = {
        "no_boxes": (_metric_line(boxes="{}"), "no box for parts"),
        "structure_list": (_metric_line(structure="[]"), '"structure" and "boxes"'),
        "boxes_string": (_metric_line(boxes='"boxes"'), '"structure" and "boxes"'),
        "box_wrong_type": (_metric_line(boxes='{"1":{"centroid":"0 0 0","extent":[1,1,1]}}'), "centroid"),
        "invalid_structure": (_metric_line(structure=_structure().replace("Wood", "Unobtainium")), "family"),
        "empty": ("\n\n", "no reference lines"),
        "many_parts": (_metric_line(structure=_chain(1500), boxes=json.dumps(
            {str(i): {"centroid": [0, 0, 0], "extent": [1, 1, 1]} for i in range(1, 1501)})), "--max-parts"),
    }
    for name, (text, expect) in refs.items():
        path = folder / f"ref_{name}.jsonl"
        path.write_text(text)
        cases.append(Case("eval metrics", name, ("eval", "metrics", "--ref", str(path), "--pred", str(good_pred),
                                                 "--out", str(out / name)), expect))
    cases += [
        Case("eval metrics", "text_not_string", ("eval", "metrics", "--ref", str(good_ref), "--pred",
                                                 str(_write(folder / "pred_type.jsonl", '{"key":"a","text":5}\n')),
                                                 "--out", str(out / "text_type")), '"text" or "structure"'),
        Case("eval metrics", "missing_ref", ("eval", "metrics", "--ref", str(folder / "absent.jsonl"), "--pred",
                                             str(good_pred), "--out", str(out / "missing")), "absent.jsonl"),
        Case("eval metrics", "ref_directory", ("eval", "metrics", "--ref", str(folder), "--pred", str(good_pred),
                                               "--out", str(out / "directory")), "metrics"),
        Case("eval metrics", "out_is_file", ("eval", "metrics", "--ref", str(good_ref), "--pred", str(good_pred),
                                             "--out", str(good_ref)), "cannot write"),
    ]
    return cases


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _png(width: int, height: int, rows: bytes | None = None) -> bytes:
    """A 1-bit greyscale PNG of ``width`` x ``height`` black pixels, compressed as it is built
    (a 12000 x 12000 image is 18 MB raw and a few kB on disk); ``rows`` replaces the pixel data."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    if rows is None:
        packer, row = zlib.compressobj(9), b"\0" * (1 + (width + 7) // 8)
        rows = b"".join(packer.compress(row) for _ in range(height)) + packer.flush()
    header = struct.pack(">IIBBBBB", width, height, 1, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", rows) + chunk(b"IEND", b"")


def _image_cases(inputs: Path, out: Path) -> list[Case]:
    """``predict`` reads the image before any model: a missing model folder is never reached."""
    folder = inputs / "images"
    folder.mkdir()
    whole = _png(2000, 2000)
    images = {
        "huge_pixels.png": (_png(12000, 12000), "pixels"),
        "giant_header.png": (_png(100_000, 100_000, rows=zlib.compress(b"\0" * 64)), "pixels"),
        "truncated.png": (whole[:len(whole) // 2], "truncated"),
        "zero_bytes.png": (b"", "not an image file"),
        "text.png": (b"this is not a picture\n", "not an image file"),
        "bad_rows.png": (_png(64, 64, rows=zlib.compress(b"\1" * 10)), "corrupt image data"),
    }
    cases = []
    for name, (data, expect) in images.items():
        (folder / name).write_bytes(data)
        stem = name.removesuffix(".png")
        cases.append(Case("predict image", stem, ("predict", str(folder / name), "--stage1", f"parts:{folder}/none",
                                                  "--structure-model", str(folder / "no_model"),
                                                  "--out", str(out / f"image_{stem}")), expect))
    cases.append(Case("predict image", "missing", ("predict", str(folder / "absent.png"), "--stage1",
                                                   f"parts:{folder}/none", "--structure-model",
                                                   str(folder / "no_model"), "--out", str(out / "image_missing")),
                      "image file not found"))
    return cases


def build_cases(root: Path) -> list[Case]:
    """Write every hostile input under ``root / "in"``; outputs may go only under ``root / "out"``."""
    inputs, out = root / "in", root / "out"
    inputs.mkdir(parents=True)
    out.mkdir()
    return (_program_cases(inputs, out) + _structure_cases(inputs, out) + _import_cases(inputs, out)
            + _metric_cases(inputs, out) + _image_cases(inputs, out) + _object_cases(inputs, out))
