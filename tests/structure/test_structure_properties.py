"""Property tests: serialisation round trips, canonical form invariants, corruptions always caught."""

import json
import math

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jax3dc.errors import StructureError
from jax3dc.structure import (
    FAMILIES,
    PLANES,
    Box,
    Joint,
    Material,
    Node,
    Relation,
    Structure,
    canonicalize,
    parse_structure,
    to_dict,
    to_json,
    validate,
)

FAST = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

coord = st.floats(-1.0, 1.0, allow_nan=False)


@st.composite
def unit_axes(draw):
    v = draw(st.tuples(coord, coord, coord).filter(lambda v: math.sqrt(sum(c * c for c in v)) > 1e-2))
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


@st.composite
def joints(draw):
    jtype = draw(st.sampled_from(["hinge", "slide"]))
    bound = 2 * math.pi if jtype == "hinge" else 1.0
    lo, hi = sorted(draw(st.tuples(st.floats(-bound, bound), st.floats(-bound, bound))))
    return Joint(jtype, draw(unit_axes()), draw(st.tuples(coord, coord, coord)), (lo, hi))


@st.composite
def structures(draw, max_parts=10):
    n = draw(st.integers(1, max_parts))
    order = draw(st.permutations(range(1, n + 1)))
    material_ids = sorted(draw(st.sets(st.integers(0, 20), min_size=1, max_size=4)))
    materials = {m: Material(draw(st.sampled_from(FAMILIES)), draw(st.text(max_size=8))) for m in material_ids}
    nodes = {}
    for k, pid in enumerate(order):
        is_root = k == 0 or draw(st.integers(0, 5)) == 0
        parent = None if is_root else order[draw(st.integers(0, k - 1))]
        joint = None if parent is None or draw(st.booleans()) else draw(joints())
        name = draw(st.none() | st.text(min_size=1, max_size=6))
        nodes[pid] = Node(parent, draw(st.sampled_from(material_ids)), joint, name)
    relations = []
    if n >= 2:
        for _ in range(draw(st.integers(0, 4))):
            a, b = draw(st.lists(st.integers(1, n), min_size=2, max_size=2, unique=True))
            rtype = draw(st.sampled_from(["symmetric", "instance", "support"]))
            relations.append(Relation(rtype, a, b, draw(st.sampled_from(PLANES)) if rtype == "symmetric" else None))
    return Structure(materials, nodes, tuple(relations))


@st.composite
def boxes_for(draw, s):
    side = st.floats(0.0, 1.0)
    # a few discrete volumes so ties happen often
    return {i: Box((0.0, 0.0, 0.0), draw(st.sampled_from([(0.5, 0.2, 0.1), (0.1, 0.5, 0.2), (0.3, 0.3, 0.3)]) |
                                             st.tuples(side, side, side))) for i in s.nodes}


def close_to_rounded(a: Structure, b: Structure) -> bool:
    """``b`` (parsed back) equals ``a`` up to the 3-decimal rounding of the JSON."""
    if a.materials != b.materials or a.relations != b.relations or a.nodes.keys() != b.nodes.keys():
        return False
    for i, na in a.nodes.items():
        nb = b.nodes[i]
        if (na.parent, na.material, na.name) != (nb.parent, nb.material, nb.name):
            return False
        if (na.joint is None) != (nb.joint is None):
            return False
        if na.joint is not None:
            ja, jb = na.joint, nb.joint
            pairs = list(zip(ja.axis, jb.axis)) + list(zip(ja.pivot, jb.pivot)) + list(zip(ja.range, jb.range))
            if ja.type != jb.type or any(abs(x - y) > 1.5e-3 for x, y in pairs):
                return False
    return True


@FAST
@given(structures())
def test_serialise_parse_identity(s):
    text = to_json(s, names=True)
    back = parse_structure(text, part_ids=s.nodes)
    assert close_to_rounded(s, back)
    assert to_json(back, names=True) == text
    # compact: no whitespace outside strings
    assert text == json.dumps(json.loads(text), separators=(",", ":"), ensure_ascii=False)
    assert json.loads(text) == to_dict(s, names=True)
    # the dictionary path agrees with the text path
    assert parse_structure(json.loads(text)) == back


@FAST
@given(st.data())
def test_canonical_form_is_idempotent_stable_and_keeps_the_articulation(data):
    s = data.draw(structures())
    boxes = data.draw(boxes_for(s))
    c = canonicalize(s, boxes)
    assert canonicalize(c, boxes) == c
    text = to_json(c)
    assert to_json(canonicalize(parse_structure(text), boxes)) == text
    # same trees (as node sets), each rooted at a part of largest volume
    def trees(x):
        out = {}
        for i in x.nodes:
            r = i
            while x.nodes[r].parent is not None:
                r = x.nodes[r].parent
            out.setdefault(r, set()).add(i)
        return out
    before, after = trees(s), trees(c)
    assert sorted(map(sorted, before.values())) == sorted(map(sorted, after.values()))
    for root, members in after.items():
        vol = lambda i: math.prod(round(e * 1e6) for e in boxes[i].extent)
        assert vol(root) == max(vol(i) for i in members)
        assert root == min(i for i in members if vol(i) == vol(root))
    # same undirected edges; a non-degenerate joint stays on its edge with pivot, |axis| and span kept
    def edges(x):
        return {frozenset((i, n.parent)): n.joint for i, n in x.nodes.items() if n.parent is not None}
    eb, ea = edges(s), edges(c)
    assert eb.keys() == ea.keys()
    for e, jb in eb.items():
        ja = ea[e]
        if jb is None or round(jb.range[0], 3) == round(jb.range[1], 3):
            assert ja is None
            continue
        assert ja.type == jb.type and ja.pivot == jb.pivot
        dot = sum(x * y for x, y in zip(ja.axis, jb.axis))
        assert abs(abs(dot) - 1) < 1e-9
        assert math.isclose(ja.range[1] - ja.range[0], jb.range[1] - jb.range[0], abs_tol=1e-12)
        written = [round(v, 3) for v in ja.axis]
        assert written[max(range(3), key=lambda k: (abs(written[k]), -k))] > 0
    # relations: instance stars, ordered symmetric pairs, sorted
    assert list(c.relations) == sorted(c.relations, key=lambda r: (r.type, r.a, r.b, r.plane or ""))
    for r in c.relations:
        if r.type == "symmetric":
            assert r.a < r.b
        if r.type == "instance":
            assert r.a < r.b and not any(q.type == "instance" and q.b == r.a for q in c.relations)


# ---- corruptions ---------------------------------------------------------------------------


def _structures_with_joint():
    return structures(max_parts=8).filter(lambda s: len(s.nodes) >= 2)


def _breaking_edits(doc: dict, s: Structure) -> list:
    """Edits each of which breaks at least one SPEC §2 rule."""
    ids = sorted(s.nodes)
    absent = max(ids) + 1
    edits = [
        ("parent_exists", lambda d: d["nodes"][str(ids[0])].__setitem__("parent", absent)),
        ("self_parent", lambda d: d["nodes"][str(ids[-1])].__setitem__("parent", ids[-1])),
        ("material_exists", lambda d: d["nodes"][str(ids[0])].__setitem__("material", 999)),
        ("family", lambda d: d["materials"][next(iter(d["materials"]))].__setitem__("family", "Plasticky")),
        ("unknown_key", lambda d: d["nodes"][str(ids[0])].__setitem__("color", "red")),
        ("unknown_key", lambda d: d.__setitem__("objects", [])),
        ("missing_key", lambda d: d["nodes"][str(ids[0])].pop("material")),
        ("value_type", lambda d: d["nodes"][str(ids[0])].__setitem__("material", True)),
        ("value_type", lambda d: d["nodes"][str(ids[0])].__setitem__("material", "0")),
        ("relation_self", lambda d: d["relations"].append({"type": "instance", "a": ids[0], "b": ids[0]})),
        ("relation_endpoint", lambda d: d["relations"].append({"type": "instance", "a": ids[0], "b": absent})),
        ("symmetric_plane", lambda d: d["relations"].append({"type": "symmetric", "a": ids[0], "b": ids[1]})),
        ("relation_plane", lambda d: d["relations"].append({"type": "support", "a": ids[0], "b": ids[1], "plane": "xy"})),
        ("part_ids", lambda d: d["nodes"].__setitem__(str(absent), {"parent": None, "material": s.nodes[ids[0]].material})),
        ("part_ids", lambda d: d["nodes"].pop(str(ids[-1]))),
    ]
    jointed = [i for i in ids if s.nodes[i].joint is not None]
    if jointed:
        j = str(jointed[0])
        edits += [
            ("axis_zero", lambda d: d["nodes"][j]["joint"].__setitem__("axis", [0, 0, 0])),
            ("axis_finite", lambda d: d["nodes"][j]["joint"].__setitem__("axis", [0, math.nan, 1])),
            ("pivot_finite", lambda d: d["nodes"][j]["joint"].__setitem__("pivot", [math.inf, 0, 1])),
            ("range_order", lambda d: d["nodes"][j]["joint"].__setitem__("range", [1.0, -1.0])),
            ("hinge_range", lambda d: d["nodes"][j]["joint"].update(type="hinge", range=[0.0, 7.0])),
            ("joint_type", lambda d: d["nodes"][j]["joint"].__setitem__("type", "revolute")),
            ("vector_shape", lambda d: d["nodes"][j]["joint"]["axis"].pop()),
            ("value_type", lambda d: d["nodes"][j]["joint"]["pivot"].__setitem__(1, None)),
            ("missing_key", lambda d: d["nodes"][j]["joint"].pop("range")),
            ("joint_without_parent", lambda d: d["nodes"][j].__setitem__("parent", None)),
        ]
    roots = s.roots()
    below = [i for i in ids if s.nodes[i].parent is not None]
    if below:
        leaf = below[-1]
        top = leaf
        while s.nodes[top].parent is not None:
            top = s.nodes[top].parent
        edits.append(("cycle", lambda d: d["nodes"][str(top)].__setitem__("parent", leaf)))
    assert roots
    return edits


@FAST
@given(st.data())
def test_breaking_edits_are_always_refused(data):
    s = data.draw(_structures_with_joint())
    edits = _breaking_edits(json.loads(to_json(s)), s)
    rule, apply = data.draw(st.sampled_from(edits))
    doc = json.loads(to_json(s))
    apply(doc)
    for form in (doc, json.dumps(doc)):
        errors = validate(form, part_ids=s.nodes)
        assert errors, rule
        assert all(isinstance(e, StructureError) for e in errors)
        assert rule in [e.rule for e in errors]
        try:
            parse_structure(form, part_ids=s.nodes)
        except StructureError:
            pass
        else:
            raise AssertionError(f"accepted a document breaking {rule}")


@FAST
@given(st.data())
def test_text_damage_gives_structure_errors_or_a_valid_structure(data):
    s = data.draw(structures(max_parts=6))
    text = to_json(s)
    op = data.draw(st.sampled_from(["truncate", "delete", "insert", "replace"]))
    k = data.draw(st.integers(0, len(text) - 1))
    if op == "truncate":
        damaged = text[:k]
    elif op == "delete":
        damaged = text[:k] + text[k + 1:]
    else:
        ch = data.draw(st.sampled_from(list('{}[]",:0123456789.-eEtruefalsnNI x')) | st.characters())
        damaged = text[:k] + ch + text[k + (op == "replace"):]
    errors = validate(damaged, part_ids=s.nodes)  # never raises
    assert all(isinstance(e, StructureError) and e.rule for e in errors)
    if op == "truncate":
        assert errors and errors[0].rule == "json"  # a proper prefix of an object is never a document
    if errors:
        try:
            parse_structure(damaged, part_ids=s.nodes)
        except StructureError as e:
            assert e.rule == errors[0].rule
        else:
            raise AssertionError("parse accepted what validate refused")
    else:
        assert isinstance(parse_structure(damaged, part_ids=s.nodes), Structure)


@FAST
@given(st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=4),
                    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner, max_size=3),
                    max_leaves=12))
def test_arbitrary_json_values_never_crash(value):
    for form in (value, json.dumps(value)):
        errors = validate(form)
        assert errors and all(isinstance(e, StructureError) for e in errors)
