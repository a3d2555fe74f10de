"""Every SPEC §2 validation rule: a document breaking it is refused with that rule and location."""

import copy
import json
import math

import pytest

from jax3dc.errors import StructureError
from jax3dc.structure import MAX_DOCUMENT_BYTES, parse_structure, to_json, validate


def valid_doc() -> dict:
    return {
        "materials": {"0": {"family": "Wood", "desc": "light oak veneer"}, "1": {"family": "Metal", "desc": "steel"}},
        "nodes": {
            "1": {"parent": None, "material": 0},
            "2": {"parent": 1, "material": 0,
                  "joint": {"type": "hinge", "axis": [0.0, 0.0, 2.0], "pivot": [0.45, -0.3, 0.0], "range": [0.0, 1.571]}},
            "3": {"parent": 2, "material": 1},
            "4": {"parent": 1, "material": 1, "joint": {"type": "slide", "axis": [0, 1, 0], "pivot": [0, 0, 0], "range": [0, 0.4]}},
            "5": {"parent": 1, "material": 1},
        },
        "relations": [{"type": "symmetric", "a": 4, "b": 5, "plane": "yz"}, {"type": "instance", "a": 3, "b": 5},
                      {"type": "support", "a": 1, "b": 3}],
    }


def edit(path, value=None, delete=False):
    """A copy of the valid document with the field at ``path`` replaced (or deleted)."""
    def make():
        doc = copy.deepcopy(valid_doc())
        obj = doc
        for k in path[:-1]:
            obj = obj[k]
        if delete:
            del obj[path[-1]]
        else:
            obj[path[-1]] = value
        return doc
    return make


def rules(doc, part_ids=None):
    return [(e.rule, e.where) for e in validate(doc, part_ids)]


def test_valid_document_parses_and_normalises_axes():
    s = parse_structure(valid_doc(), part_ids=[1, 2, 3, 4, 5])
    assert validate(valid_doc(), part_ids=range(1, 6)) == []
    assert s.nodes[2].joint.axis == (0.0, 0.0, 1.0)
    assert s.nodes[2].parent == 1 and s.nodes[1].parent is None
    assert s.materials[1].family == "Metal"
    assert [r.type for r in s.relations] == ["symmetric", "instance", "support"]
    # JSON text and the dictionary give the same structure
    assert parse_structure(json.dumps(valid_doc())) == s


CASES = [
    # (id, make document, part_ids, expected (rule, where))
    ("top_level_list", lambda: [1, 2], None, ("top_level", "")),
    ("missing_nodes", edit(["nodes"], delete=True), None, ("missing_key", "document")),
    ("missing_materials", edit(["materials"], delete=True), None, ("missing_key", "document")),
    ("unknown_top_key", edit(["extra"], 1), None, ("unknown_key", "document")),
    ("unknown_node_key", edit(["nodes", "3", "colour"], "red"), None, ("unknown_key", "node 3")),
    ("unknown_joint_key", edit(["nodes", "2", "joint", "damping"], 0.1), None, ("unknown_key", "node 2 joint")),
    ("unknown_material_key", edit(["materials", "0", "density"], 700), None, ("unknown_key", "material 0")),
    ("unknown_relation_key", edit(["relations", 1, "weight"], 1), None, ("unknown_key", "relation 1")),
    ("missing_parent", edit(["nodes", "3", "parent"], delete=True), None, ("missing_key", "node 3")),
    ("missing_axis", edit(["nodes", "2", "joint", "axis"], delete=True), None, ("missing_key", "node 2 joint")),
    ("nodes_not_object", edit(["nodes"], [1, 2]), None, ("value_type", "nodes")),
    ("relations_not_list", edit(["relations"], {}), None, ("value_type", "relations")),
    ("parent_string", edit(["nodes", "3", "parent"], "2"), None, ("value_type", "node 3 parent")),
    ("parent_bool", edit(["nodes", "3", "parent"], True), None, ("value_type", "node 3 parent")),
    ("parent_float", edit(["nodes", "3", "parent"], 2.0), None, ("value_type", "node 3 parent")),
    ("material_bool", edit(["nodes", "3", "material"], False), None, ("value_type", "node 3 material")),
    ("axis_bool", edit(["nodes", "2", "joint", "axis"], [0, 0, True]), None, ("value_type", "node 2 joint.axis[2]")),
    ("pivot_string", edit(["nodes", "2", "joint", "pivot"], [0, "0.1", 0]), None, ("value_type", "node 2 joint.pivot[1]")),
    ("range_null", edit(["nodes", "2", "joint", "range"], [None, 1]), None, ("value_type", "node 2 joint.range[0]")),
    ("axis_two", edit(["nodes", "2", "joint", "axis"], [0, 1]), None, ("vector_shape", "node 2 joint.axis")),
    ("range_three", edit(["nodes", "2", "joint", "range"], [0, 1, 2]), None, ("vector_shape", "node 2 joint.range")),
    ("axis_scalar", edit(["nodes", "2", "joint", "axis"], 1.0), None, ("value_type", "node 2 joint.axis")),
    ("node_id_word", edit(["nodes", "six"], {"parent": None, "material": 0}), None, ("id_format", 'node "six"')),
    ("node_id_zero", edit(["nodes", "0"], {"parent": None, "material": 0}), None, ("id_format", 'node "0"')),
    ("node_id_padded", edit(["nodes", "06"], {"parent": None, "material": 0}), None, ("id_format", 'node "06"')),
    ("material_id_negative", edit(["materials", "-1"], {"family": "Wood"}), None, ("id_format", 'material "-1"')),
    ("no_nodes", edit(["nodes"], {}), None, ("no_nodes", "nodes")),
    ("part_ids_missing", valid_doc, [1, 2, 3, 4, 5, 6], ("part_ids", "nodes")),
    ("part_ids_extra", valid_doc, [1, 2, 3, 4], ("part_ids", "nodes")),
    ("parent_missing", edit(["nodes", "3", "parent"], 9), None, ("parent_exists", "node 3 parent")),
    ("self_parent", edit(["nodes", "3", "parent"], 3), None, ("self_parent", "node 3 parent")),
    ("material_missing", edit(["nodes", "3", "material"], 7), None, ("material_exists", "node 3 material")),
    ("family_unknown", edit(["materials", "1", "family"], "Steel"), None, ("family", "material 1 family")),
    ("family_lowercase", edit(["materials", "1", "family"], "metal"), None, ("family", "material 1 family")),
    ("family_missing", edit(["materials", "1", "family"], delete=True), None, ("missing_key", "material 1")),
    ("desc_number", edit(["materials", "1", "desc"], 3), None, ("value_type", "material 1 desc")),
    ("joint_on_root", edit(["nodes", "1", "joint"], {"type": "hinge", "axis": [0, 0, 1], "pivot": [0, 0, 0],
                                                    "range": [0, 1]}), None, ("joint_without_parent", "node 1 joint")),
    ("joint_type", edit(["nodes", "2", "joint", "type"], "ball"), None, ("joint_type", "node 2 joint.type")),
    ("axis_nan", edit(["nodes", "2", "joint", "axis"], [0, math.nan, 1]), None, ("axis_finite", "node 2 joint.axis")),
    ("axis_inf", edit(["nodes", "2", "joint", "axis"], [0, 0, math.inf]), None, ("axis_finite", "node 2 joint.axis")),
    ("axis_zero", edit(["nodes", "2", "joint", "axis"], [0, 0, 0]), None, ("axis_zero", "node 2 joint.axis")),
    ("pivot_nan", edit(["nodes", "2", "joint", "pivot"], [0, math.nan, 1]), None, ("pivot_finite", "node 2 joint.pivot")),
    ("range_inf", edit(["nodes", "4", "joint", "range"], [0, math.inf]), None, ("range_finite", "node 4 joint.range")),
    ("range_order", edit(["nodes", "2", "joint", "range"], [1.0, 0.5]), None, ("range_order", "node 2 joint.range")),
    ("hinge_range_hi", edit(["nodes", "2", "joint", "range"], [0, 6.3]), None, ("hinge_range", "node 2 joint.range")),
    ("hinge_range_lo", edit(["nodes", "2", "joint", "range"], [-6.3, 0]), None, ("hinge_range", "node 2 joint.range")),
    ("relation_type", edit(["relations", 1, "type"], "copy"), None, ("relation_type", "relation 1 type")),
    ("relation_endpoint", edit(["relations", 1, "b"], 12), None, ("relation_endpoint", "relation 1 b")),
    ("relation_self", edit(["relations", 1, "b"], 3), None, ("relation_self", "relation 1")),
    ("relation_a_string", edit(["relations", 1, "a"], "3"), None, ("value_type", "relation 1 a")),
    ("symmetric_no_plane", edit(["relations", 0, "plane"], delete=True), None, ("symmetric_plane", "relation 0")),
    ("symmetric_bad_plane", edit(["relations", 0, "plane"], "zx"), None, ("symmetric_plane", "relation 0 plane")),
    ("instance_with_plane", edit(["relations", 1, "plane"], "xy"), None, ("relation_plane", "relation 1 plane")),
    ("support_with_plane", edit(["relations", 2, "plane"], "xy"), None, ("relation_plane", "relation 2 plane")),
    ("relation_not_object", edit(["relations", 1], [3, 5]), None, ("value_type", "relation 1")),
    ("node_not_object", edit(["nodes", "3"], 2), None, ("value_type", "node 3")),
]


@pytest.mark.parametrize("make,part_ids,expected", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_each_rule_is_reported_with_its_location(make, part_ids, expected):
    doc = make()
    found = rules(doc, part_ids)
    assert expected in found, found
    with pytest.raises(StructureError) as info:
        parse_structure(doc, part_ids)
    assert info.value.rule in {rule for rule, _ in found}
    # the same problem is found in the JSON text (NaN / Infinity written the way Python's json does)
    assert expected in rules(json.dumps(doc), part_ids)


def test_hinge_range_limit_is_inclusive_and_slides_have_no_angle_limit():
    assert validate(edit(["nodes", "2", "joint", "range"], [-2 * math.pi, 2 * math.pi])()) == []
    assert validate(edit(["nodes", "4", "joint", "range"], [-10.0, 10.0])()) == []


def test_cycle_is_named():
    doc = valid_doc()
    doc["nodes"]["1"]["parent"] = 3  # 1 -> 3 -> 2 -> 1
    errors = validate(doc)
    cycles = [e for e in errors if e.rule == "cycle"]
    assert len(cycles) == 1
    assert "1 -> 3 -> 2 -> 1" in str(cycles[0])
    assert cycles[0].where == "node 1 parent"
    # node 2 carries a joint though its ancestry is cyclic: only the cycle is wrong, no spurious errors
    assert [e.rule for e in errors] == ["cycle"]


def test_two_cycles_both_named():
    doc = valid_doc()
    doc["nodes"]["1"]["parent"] = 2  # 1 <-> 2
    doc["nodes"]["4"]["parent"] = 5
    doc["nodes"]["5"]["parent"] = 4
    msgs = [str(e) for e in validate(doc) if e.rule == "cycle"]
    assert len(msgs) == 2
    assert any("1 -> 2 -> 1" in m for m in msgs) and any("4 -> 5 -> 4" in m for m in msgs)


def test_all_problems_are_reported_in_document_order():
    doc = valid_doc()
    doc["materials"]["0"]["family"] = "Wod"
    doc["nodes"]["2"]["joint"]["axis"] = [0, 0, 0]
    doc["nodes"]["3"]["material"] = 9
    doc["relations"][0]["a"] = 99
    found = [e.rule for e in validate(doc)]
    assert found == ["family", "axis_zero", "material_exists", "relation_endpoint"]
    with pytest.raises(StructureError) as info:
        parse_structure(doc)
    assert info.value.rule == "family"


def test_truncated_json_names_line_and_column():
    text = json.dumps(valid_doc(), indent=1)
    cut = text[: len(text) // 2]
    (err,) = validate(cut)
    assert err.rule == "json"
    line = cut.count("\n") + 1
    assert err.where.startswith(f"line {line} column")
    assert "truncated" in err.message


def test_json_syntax_error_location():
    (err,) = validate('{"materials": {},\n "nodes": {"1": {"parent": null "material": 0}}}')
    assert (err.rule, err.where) == ("json", "line 2 column 33")


def test_duplicate_keys_are_refused():
    text = '{"materials":{"0":{"family":"Wood"}},"nodes":{"1":{"parent":null,"material":0},"1":{"parent":null,"material":0}}}'
    assert ("duplicate_key", 'key "1"') in rules(text)
    # also a string key and an int key for the same id in a Python dictionary
    doc = valid_doc()
    doc["nodes"][5] = doc["nodes"]["5"]
    assert ("duplicate_key", "node 5") in rules(doc)


def test_bytes_and_non_utf8():
    assert validate(json.dumps(valid_doc()).encode()) == []
    assert [e.rule for e in validate(b'{"nodes": "\xff"}')] == ["json"]


def test_large_document_rejected_with_size_message():
    big = json.dumps(valid_doc())[:-1] + ',"pad":"' + "x" * (10 * 1024 * 1024) + '"}'
    errors = validate(big)  # refused by its size before parsing; time in bench/structure_validate.py
    assert [e.rule for e in errors] == ["document_size"]
    assert str(MAX_DOCUMENT_BYTES) in str(errors[0])


def test_largest_allowed_document_parses_without_recursion():
    n = 3000  # ~ 0.4 MB with a joint on every node: far beyond any real scene
    nodes = {"1": {"parent": None, "material": 0}}
    for i in range(2, n + 1):
        nodes[str(i)] = {"parent": i - 1, "material": 0,  # one long chain: depth n
                         "joint": {"type": "slide", "axis": [0.577, 0.577, 0.577], "pivot": [0.1, 0.2, 0.3], "range": [0, 0.5]}}
    text = json.dumps({"materials": {"0": {"family": "Wood"}}, "nodes": nodes, "relations": []})
    assert len(text) < MAX_DOCUMENT_BYTES
    s = parse_structure(text, part_ids=range(1, n + 1))  # its time: bench/structure_validate.py
    assert len(s.joints()) == n - 1
    # a long cycle is found without recursion
    nodes["1"]["parent"] = n
    (err,) = validate({"materials": {"0": {"family": "Wood"}}, "nodes": nodes})
    assert err.rule == "cycle"


def test_huge_integer_literal_is_a_structure_error():
    (err,) = validate('{"materials": {}, "nodes": ' + "1" * 5000 + "}")
    assert err.rule == "json" and "digits" in err.message
    doc = valid_doc()
    doc["nodes"]["2"]["joint"]["pivot"] = [10**400, 0, 0]  # an int too large for a float
    assert ("pivot_finite", "node 2 joint.pivot") in rules(doc)


def test_many_relations_check():
    doc = valid_doc()
    doc["relations"] = [{"type": "instance", "a": 1 + k % 5, "b": 1 + (k + 1) % 5} for k in range(20000)]
    assert validate(doc) == []  # its time: bench/structure_validate.py


def test_deeply_nested_json_is_a_structure_error():
    errors = validate("[" * 100000 + "]" * 100000)
    assert errors and errors[0].rule in {"json", "top_level"}


def test_missing_relations_is_allowed_and_written_back():
    doc = valid_doc()
    del doc["relations"]
    s = parse_structure(doc)
    assert s.relations == ()
    assert to_json(s).endswith('"relations":[]}')


def test_names_are_kept_only_when_asked():
    doc = valid_doc()
    doc["nodes"]["3"]["name"] = "door handle"
    s = parse_structure(doc)
    assert s.nodes[3].name == "door handle"
    assert "handle" not in to_json(s)
    assert '"name":"door handle"' in to_json(s, names=True)
    assert parse_structure(to_json(s, names=True)) == s
