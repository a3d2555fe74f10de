"""Parsing and validation of a structure document against every rule of SPEC §2, and the
document in a model's reply (``json_text``: the text step between generation and
``parse_structure``, shared by ``predict``, the verified choice and evaluation's scoring).

A predicted document that breaks any rule is a parse failure, so the checker is strict (unknown
keys, booleans where numbers belong, non-finite numbers and duplicate keys are all refused) and
reports every problem with a stable rule name and a location, in document order.

Rule names (``StructureError.rule``):
  document_size, json, duplicate_key, top_level, missing_key, unknown_key, value_type,
  vector_shape, id_format, no_nodes, part_ids, parent_exists, self_parent, cycle,
  material_exists, family, joint_without_parent, joint_type, axis_finite, axis_zero,
  pivot_finite, range_finite, range_order, hinge_range, relation_type, relation_endpoint,
  relation_self, symmetric_plane, relation_plane, text.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping

from jax3dc.errors import StructureError
from jax3dc.structure.schema import (
    FAMILIES,
    JOINT_TYPES,
    PLANES,
    RELATION_TYPES,
    Joint,
    Material,
    Node,
    Relation,
    Structure,
)

# The largest document we read. A target within the model's 8192-token context is under ~32 KB
# and a 1000-part scene with a joint on every node is about 150 KB; 1 MiB leaves ample room while
# keeping a hostile or runaway document (e.g. a 10 MB generation) from costing seconds to check.
MAX_DOCUMENT_BYTES = 1 << 20

HINGE_LIMIT = 2 * math.pi  # radians; a hinge range lies within [-2π, 2π]

TOP_KEYS_REQUIRED = ("materials", "nodes")
TOP_KEYS_OPTIONAL = ("relations",)
MATERIAL_KEYS_REQUIRED = ("family",)
MATERIAL_KEYS_OPTIONAL = ("desc",)
NODE_KEYS_REQUIRED = ("parent", "material")
NODE_KEYS_OPTIONAL = ("joint", "name")
JOINT_KEYS_REQUIRED = ("type", "axis", "pivot", "range")
RELATION_KEYS_REQUIRED = ("type", "a", "b")
RELATION_KEYS_OPTIONAL = ("plane",)

_DECIMAL_ID = re.compile(r"(0|[1-9][0-9]{0,17})")
# Chat-template end markers a generation may still carry, and a Markdown code fence around JSON.
_END_MARKERS = re.compile(r"(<\|im_end\|>|<\|endoftext\|>)\s*$")
_FENCE = re.compile(r"^```(?:json)?\s*\n?(.*?)\n?```$", re.DOTALL)


def json_text(raw: str) -> str:
    """The JSON document in a raw generation: end-of-turn markers and a code fence removed."""
    text = _END_MARKERS.sub("", raw.strip()).strip()
    fenced = _FENCE.match(text)
    return fenced.group(1).strip() if fenced else text


def _show(value: object, limit: int = 40) -> str:
    text = json.dumps(value, default=repr) if not isinstance(value, float) else repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


class _Checker:
    """Walks one document, collecting problems and building the Structure if there are none."""

    def __init__(self) -> None:
        self.errors: list[StructureError] = []
        # What each node says about its links, recorded even when another field of it is broken,
        # so that tree and reference rules are checked on every node.
        self.parents: dict[int, int | None] = {}
        self.material_refs: dict[int, int] = {}
        self.jointed: set[int] = set()

    def fail(self, rule: str, where: str, message: str) -> None:
        self.errors.append(StructureError(rule, where, message))

    # ---- primitive values -------------------------------------------------------------------

    def keys(self, obj: Mapping, where: str, required: Iterable[str], optional: Iterable[str] = ()) -> bool:
        required = tuple(required)
        allowed = set(required) | set(optional)
        ok = True
        for k in required:
            if k not in obj:
                self.fail("missing_key", where, f"missing key {k!r}")
                ok = False
        for k in obj:
            if k not in allowed:
                self.fail("unknown_key", where, f"unknown key {_show(k)} (allowed: {', '.join(sorted(allowed))})")
        return ok

    def mapping(self, value: object, where: str) -> bool:
        if isinstance(value, Mapping):
            return True
        self.fail("value_type", where, f"must be an object, got {_show(value)}")
        return False

    def integer(self, value: object, where: str) -> int | None:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        self.fail("value_type", where, f"must be an integer id, got {_show(value)}")
        return None

    def number(self, value: object, where: str) -> float | None:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            try:
                return float(value)
            except OverflowError:  # an integer literal too large for a float
                return math.inf
        self.fail("value_type", where, f"must be a number, got {_show(value)}")
        return None

    def string(self, value: object, where: str) -> str | None:
        if isinstance(value, str):
            try:
                value.encode("utf-8")
            except UnicodeEncodeError as e:  # JSON's "\\ud800" escape decodes to a lone surrogate
                self.fail("text", where, f"is not valid Unicode text (a lone surrogate at character {e.start})")
                return None
            return value
        self.fail("value_type", where, f"must be a string, got {_show(value)}")
        return None

    def vector(self, value: object, where: str, size: int) -> tuple[float, ...] | None:
        if not isinstance(value, list | tuple):
            self.fail("value_type", where, f"must be a list of {size} numbers, got {_show(value)}")
            return None
        if len(value) != size:
            self.fail("vector_shape", where, f"must have {size} numbers, got {len(value)}")
            return None
        out = [self.number(v, f"{where}[{k}]") for k, v in enumerate(value)]
        return None if any(v is None for v in out) else tuple(out)

    def id_key(self, key: object, where: str, smallest: int) -> int | None:
        """A dictionary key that names an id: a decimal string in JSON (an int is accepted from Python)."""
        if isinstance(key, int) and not isinstance(key, bool):
            value = key
        elif isinstance(key, str) and _DECIMAL_ID.fullmatch(key):
            value = int(key)
        else:
            self.fail("id_format", where, f"key {_show(key)} is not a decimal integer id")
            return None
        if value < smallest:
            self.fail("id_format", where, f"id {value} is below {smallest}")
            return None
        return value

    def id_table(self, table: Mapping, kind: str, smallest: int) -> dict[int, object]:
        out: dict[int, object] = {}
        for key, value in table.items():
            i = self.id_key(key, f"{kind} {_show(key)}", smallest)
            if i is None:
                continue
            if i in out:
                self.fail("duplicate_key", f"{kind} {i}", f"{kind} id {i} is given twice")
                continue
            out[i] = value
        return dict(sorted(out.items()))

    # ---- sections ---------------------------------------------------------------------------

    def material(self, mid: int, value: object) -> Material | None:
        where = f"material {mid}"
        if not self.mapping(value, where):
            return None
        self.keys(value, where, MATERIAL_KEYS_REQUIRED, MATERIAL_KEYS_OPTIONAL)
        family = self.string(value["family"], f"{where} family") if "family" in value else None
        desc = self.string(value.get("desc", ""), f"{where} desc")
        if family is not None and family not in FAMILIES:
            self.fail("family", f"{where} family", f"unknown family {_show(family)} (one of: {', '.join(FAMILIES)})")
            return None
        if family is None or desc is None:
            return None
        return Material(family, desc)

    def joint(self, pid: int, value: object) -> Joint | None:
        where = f"node {pid} joint"
        if not self.mapping(value, where):
            return None
        if not self.keys(value, where, JOINT_KEYS_REQUIRED):
            return None
        jtype = self.string(value["type"], f"{where}.type")
        if jtype is not None and jtype not in JOINT_TYPES:
            self.fail("joint_type", f"{where}.type", f"unknown joint type {_show(jtype)} (one of: {', '.join(JOINT_TYPES)})")
            jtype = None
        axis = self.vector(value["axis"], f"{where}.axis", 3)
        if axis is not None:
            if not all(math.isfinite(c) for c in axis):
                self.fail("axis_finite", f"{where}.axis", f"axis {list(axis)} is not finite")
                axis = None
            else:
                norm = math.sqrt(sum(c * c for c in axis))
                if norm == 0 or not math.isfinite(norm):
                    self.fail("axis_zero", f"{where}.axis", "axis is the zero vector" if norm == 0
                              else "axis is too long to normalise")
                    axis = None
                else:
                    axis = tuple(c / norm for c in axis)
        pivot = self.vector(value["pivot"], f"{where}.pivot", 3)
        if pivot is not None and not all(math.isfinite(c) for c in pivot):
            self.fail("pivot_finite", f"{where}.pivot", f"pivot {list(pivot)} is not finite")
            pivot = None
        rng = self.vector(value["range"], f"{where}.range", 2)
        if rng is not None:
            lo, hi = rng
            if not (math.isfinite(lo) and math.isfinite(hi)):
                self.fail("range_finite", f"{where}.range", f"range {list(rng)} is not finite")
                rng = None
            elif lo > hi:
                self.fail("range_order", f"{where}.range", f"range lower bound {lo} exceeds upper bound {hi}")
                rng = None
            elif jtype == "hinge" and (lo < -HINGE_LIMIT or hi > HINGE_LIMIT):
                self.fail("hinge_range", f"{where}.range",
                          f"hinge range [{lo}, {hi}] leaves [-2pi, 2pi] radians")
                rng = None
        if jtype is None or axis is None or pivot is None or rng is None:
            return None
        return Joint(jtype, axis, pivot, rng)

    def node(self, pid: int, value: object) -> Node | None:
        where = f"node {pid}"
        if not self.mapping(value, where):
            return None
        complete = self.keys(value, where, NODE_KEYS_REQUIRED, NODE_KEYS_OPTIONAL)
        parent = value.get("parent")
        if parent is not None:
            parent = self.integer(parent, f"{where} parent")
            complete = complete and parent is not None
        if "parent" in value and (parent is not None or value["parent"] is None):
            self.parents[pid] = parent
        material = self.integer(value["material"], f"{where} material") if "material" in value else None
        if material is not None:
            self.material_refs[pid] = material
        joint = None
        if value.get("joint") is not None:
            self.jointed.add(pid)
            joint = self.joint(pid, value["joint"])
            complete = complete and joint is not None
        name = value.get("name")
        if name is not None:
            name = self.string(name, f"{where} name")
            complete = complete and name is not None
        if not complete or material is None:
            return None
        return Node(parent, material, joint, name)

    def relation(self, k: int, value: object) -> Relation | None:
        where = f"relation {k}"
        if not self.mapping(value, where):
            return None
        if not self.keys(value, where, RELATION_KEYS_REQUIRED, RELATION_KEYS_OPTIONAL):
            return None
        rtype = self.string(value["type"], f"{where} type")
        if rtype is not None and rtype not in RELATION_TYPES:
            self.fail("relation_type", f"{where} type",
                      f"unknown relation type {_show(rtype)} (one of: {', '.join(RELATION_TYPES)})")
            rtype = None
        a = self.integer(value["a"], f"{where} a")
        b = self.integer(value["b"], f"{where} b")
        plane = value.get("plane")
        if rtype == "symmetric":
            if plane is None:
                self.fail("symmetric_plane", where, f"a symmetric relation needs a plane (one of: {', '.join(PLANES)})")
            elif plane not in PLANES:
                self.fail("symmetric_plane", f"{where} plane", f"unknown plane {_show(plane)} (one of: {', '.join(PLANES)})")
                plane = None
        elif rtype is not None and "plane" in value:
            self.fail("relation_plane", f"{where} plane", f"a {rtype} relation has no plane")
        if rtype is None or a is None or b is None or (rtype == "symmetric" and plane is None):
            return None
        return Relation(rtype, a, b, plane if rtype == "symmetric" else None)

    # ---- whole document ---------------------------------------------------------------------

    def document(self, doc: object, part_ids: Iterable[int] | None) -> Structure | None:
        if not isinstance(doc, Mapping):
            self.fail("top_level", "", f"the document must be a JSON object, got {type(doc).__name__}")
            return None
        self.keys(doc, "document", TOP_KEYS_REQUIRED, TOP_KEYS_OPTIONAL)

        materials: dict[int, Material] = {}
        material_keys: set[int] | None = None
        materials_ok = "materials" in doc and self.mapping(doc["materials"], "materials")
        if materials_ok:
            n_errors = len(self.errors)
            material_table = self.id_table(doc["materials"], "material", 0)
            material_keys = set(material_table)
            for mid, value in material_table.items():
                m = self.material(mid, value)
                if m is not None:
                    materials[mid] = m
            materials_ok = len(self.errors) == n_errors

        nodes: dict[int, Node] = {}
        node_keys: list[int] = []
        nodes_ok = "nodes" in doc and self.mapping(doc["nodes"], "nodes")
        if nodes_ok:
            n_errors = len(self.errors)
            table = self.id_table(doc["nodes"], "node", 1)
            node_keys = list(table)
            for pid, value in table.items():
                n = self.node(pid, value)
                if n is not None:
                    nodes[pid] = n
            nodes_ok = len(self.errors) == n_errors
            if not table and n_errors == len(self.errors):
                self.fail("no_nodes", "nodes", "the structure has no nodes")

        if part_ids is not None and "nodes" in doc and isinstance(doc["nodes"], Mapping):
            self.part_id_match(node_keys, part_ids)
        node_set = set(node_keys)
        self.tree(node_set)
        if material_keys is not None:
            for pid, mid in self.material_refs.items():
                if mid not in material_keys:
                    self.fail("material_exists", f"node {pid} material", f"material {mid} is not in materials")

        relations: list[Relation] = []
        relations_ok = True
        if "relations" in doc:
            raw = doc["relations"]
            if not isinstance(raw, list | tuple):
                self.fail("value_type", "relations", f"must be a list, got {_show(raw)}")
                relations_ok = False
            else:
                for k, value in enumerate(raw):
                    r = self.relation(k, value)
                    if r is None:
                        relations_ok = False
                        continue
                    relations.append(r)
                    if isinstance(doc.get("nodes"), Mapping):
                        for end, pid in (("a", r.a), ("b", r.b)):
                            if pid not in node_set:
                                self.fail("relation_endpoint", f"relation {k} {end}", f"part {pid} is not a node")
                    if r.a == r.b:
                        self.fail("relation_self", f"relation {k}", f"relation links part {r.a} to itself")

        if self.errors or not (materials_ok and nodes_ok and relations_ok):
            return None
        return Structure(materials, nodes, tuple(relations))

    def part_id_match(self, node_ids: list[int], part_ids: Iterable[int]) -> None:
        want = set(int(i) for i in part_ids)
        have = set(node_ids)
        missing, extra = sorted(want - have), sorted(have - want)
        if missing or extra:
            parts = []
            if missing:
                parts.append(f"missing parts {_id_list(missing)}")
            if extra:
                parts.append(f"nodes {_id_list(extra)} are not parts")
            self.fail("part_ids", "nodes", f"node ids must be exactly the part ids: {'; '.join(parts)}")

    def tree(self, node_ids: set[int]) -> None:
        """Parents exist, no node is its own parent, the parent map has no cycle, joints have parents."""
        parents = self.parents
        for pid in sorted(parents):
            parent = parents[pid]
            if parent is None:
                if pid in self.jointed:
                    self.fail("joint_without_parent", f"node {pid} joint", "a root node (parent null) cannot have a joint")
            elif parent == pid:
                self.fail("self_parent", f"node {pid} parent", f"node {pid} is its own parent")
            elif parent not in node_ids:
                self.fail("parent_exists", f"node {pid} parent", f"parent {parent} is not a node")
        # Cycles: follow parent links; each node is visited once overall (linear in the node count).
        state: dict[int, int] = {}  # 1 = on the current path, 2 = finished
        for start in sorted(parents):
            path: list[int] = []
            cur: int | None = start
            while cur is not None and cur in parents and cur not in state:
                state[cur] = 1
                path.append(cur)
                parent = parents[cur]
                cur = None if parent == cur else parent
            if cur is not None and state.get(cur) == 1:
                cycle = path[path.index(cur):]
                k = cycle.index(min(cycle))
                cycle = cycle[k:] + cycle[:k]
                shown = [*cycle, cycle[0]] if len(cycle) <= 10 else [*cycle[:5], "...", *cycle[-4:], cycle[0]]
                self.fail("cycle", f"node {cycle[0]} parent", f"parent cycle of {len(cycle)} nodes "
                          + " -> ".join(str(i) for i in shown) if len(cycle) > 10
                          else "parent cycle " + " -> ".join(str(i) for i in shown))
            for p in path:
                state[p] = 2


def _id_list(ids: list[int], limit: int = 10) -> str:
    text = ", ".join(str(i) for i in ids[:limit])
    return text + (f", ... ({len(ids)} in all)" if len(ids) > limit else "")


_UNREADABLE = object()  # what _load_text returns when the text is not a JSON document


def _load_text(text: str | bytes, checker: _Checker) -> object:
    size = len(text) if isinstance(text, bytes) else len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_DOCUMENT_BYTES:
        checker.fail("document_size", "", f"the document is {size} bytes; the limit is {MAX_DOCUMENT_BYTES} "
                     "(MAX_DOCUMENT_BYTES: far above any real structure)")
        return _UNREADABLE
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as e:
            checker.fail("json", f"byte {e.start}", "the document is not UTF-8 text")
            return _UNREADABLE

    def pairs(items: list[tuple[str, object]]) -> dict:
        out: dict = {}
        for k, v in items:
            if k in out:
                checker.fail("duplicate_key", f"key {_show(k)}", f"key {_show(k)} appears twice in one object")
            out[k] = v
        return out

    try:
        return json.loads(text, object_pairs_hook=pairs)
    except json.JSONDecodeError as e:
        ends_early = e.pos >= len(text.rstrip()) or e.msg.startswith("Unterminated string")
        hint = " (the document ends early: truncated?)" if ends_early else ""
        checker.fail("json", f"line {e.lineno} column {e.colno}", f"invalid JSON: {e.msg}{hint}")
    except RecursionError:
        checker.fail("json", "", "invalid JSON: nested too deeply")
    except ValueError as e:  # e.g. an integer literal longer than Python's digit limit
        checker.fail("json", "", f"invalid JSON: {e}")
    return _UNREADABLE


def read_json(text: str | bytes) -> object:
    """The JSON value of ``text`` under this module's reading rules (size cap, UTF-8, no duplicate
    keys), for documents that ride beside a structure (an edit patch, jax3dc.edits); raises the
    first problem as a StructureError (rules document_size, json, duplicate_key)."""
    checker = _Checker()
    loaded = _load_text(text, checker)
    if checker.errors:
        raise checker.errors[0]
    return loaded


def _check(doc: str | bytes | Mapping, part_ids: Iterable[int] | None) -> tuple[Structure | None, list[StructureError]]:
    checker = _Checker()
    if isinstance(doc, str | bytes):
        loaded = _load_text(doc, checker)
        if loaded is _UNREADABLE:
            return None, checker.errors
    else:
        loaded = doc
    if part_ids is not None:
        part_ids = list(part_ids)
    s = checker.document(loaded, part_ids)
    return s, checker.errors


def validate(doc: str | bytes | Mapping, part_ids: Iterable[int] | None = None) -> list[StructureError]:
    """Every problem of ``doc`` (JSON text or a parsed dictionary), in document order; [] if valid.

    ``part_ids``: the part ids of the segmentation; when given, node ids must be exactly these.
    """
    return _check(doc, part_ids)[1]


def parse_structure(doc: str | bytes | Mapping, part_ids: Iterable[int] | None = None) -> Structure:
    """The Structure of a valid document (axes normalised); raises the first problem found."""
    s, errors = _check(doc, part_ids)
    if errors:
        raise errors[0]
    assert s is not None
    return s
