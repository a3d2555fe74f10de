"""`jax3dc edit DIR [PATCH.json]`: fix a predicted joint by hand, then re-check and re-export."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

DESCRIPTION = """\
Edit a joint of a `jax3dc predict` output folder DIR by hand: PATCH.json (or - for standard input)
names one part and sets its joint's type, axis, hinge line or range, or its parent:

  {"part": 3, "ops": [{"op": "set_line", "value": "edge +x -y"}]}

  set_type    "hinge", "slide" or "fixed" (fixed removes the joint)
  set_axis    "+x" "-x" "+y" "-y" "+z" "-z" (the frame: +z up, the front faces -y), or [x, y, z]
  set_line    one of the lines of the part's box along the axis ("centre", "face -x",
              "edge +x -y", ...: run `jax3dc edit DIR` to list them), or a point [x, y, z] on it
  set_range   [lo, hi]: radians for a hinge, normalised units for a slide
  set_parent  a part id, or null

The patch is checked like any structure (SPEC §2); a bad one is one error line naming its place in
the patch, and nothing is written. A new joint needs set_axis; it, or one that changes type, gets
a default range, and a hinge or slide moved to another line is turned to open away from its
parent, unless the patch sets the range. Then the physics check runs again and every file made from
the structure is rewritten (structure.json, object.urdf / .xml / .usda / .glb, object_blender.py,
physics.json, report, viewer.html); they replace the old ones only once all are written, and
DIR/edits.jsonl keeps each patch with the structure it replaced.

Without PATCH, prints each part's joint and the lines it can be put on.
"""


def _numbers(values) -> str:
    return "[" + ", ".join(f"{float(v):.3f}" for v in values) + "]"


def describe(folder: Path) -> list[str]:
    """One line per part: its parent and joint, and the named lines along its axis (the one it is
    on marked with *), so a person can write a patch."""
    from jax3dc.edits.folder import joint_rows, load_object  # lazy: the exporters and physics (0.15 s), see run

    lines = []
    for row in joint_rows(load_object(folder)):
        label = f"part {row.part}" + (f" ({row.name})" if row.name is not None else "")
        if row.type == "root":
            lines.append(f"{label}: root")
            continue
        if row.type == "fixed":
            lines.append(f"{label}: fixed to part {row.parent}")
            continue
        unit = "rad" if row.type == "hinge" else "nu"
        lines.append(f"{label}: {row.type} on part {row.parent}, axis {row.axis_name or _numbers(row.axis)}, line "
                     f"{row.line or 'through ' + _numbers(row.pivot)}, range {_numbers(row.range)} {unit}")
        names = [name + ("*" if name == row.line else "") for name in row.lines_along_axis()]
        if names:
            lines.append("    lines: " + ", ".join(names))
    return lines


def run(args: argparse.Namespace) -> int:
    folder = Path(args.folder)
    if args.patch is None:
        print("\n".join(describe(folder)))
        return 0
    # lazy: the exporters and the physics check (0.15 s), which `jax3dc --help` should not pay for
    from jax3dc.edits.folder import edit_folder

    patch = sys.stdin.buffer.read() if args.patch == "-" else Path(args.patch).read_bytes()
    result = edit_folder(folder, patch)
    joint = result.structure.nodes[result.patch.part].joint
    now = "fixed to its parent" if joint is None else f"{joint.type}, axis {_numbers(joint.axis)}, " \
        f"pivot {_numbers(joint.pivot)}, range {_numbers(joint.range)}"
    verdict = "passes" if result.verdict.ok else "fails"
    print(f"part {result.patch.part}: {now}")
    print(f"rewrote {len(result.files)} outputs in {folder}; the physics check {verdict} (see physics.json)")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("edit", help="fix a predicted joint by hand; re-check and re-export",
                              description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("folder", metavar="DIR", help="a `jax3dc predict` output folder")
    p.add_argument("patch", metavar="PATCH.json", nargs="?",
                   help="the edit (- reads standard input); without it, list the parts, joints and lines")
    p.set_defaults(func=run)
