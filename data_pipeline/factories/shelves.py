"""Instance-heavy shelving (paper §3.3): cell shelf, large shelf, simple bookcase, triangle shelf.

Every board, divider, upright and book is its own part, and copies of one design share a
twin key, so these objects carry many `instance` relations.
"""

from __future__ import annotations

import math

import numpy as np

from data_pipeline.factories import kit
from data_pipeline.factories.kit import u
from data_pipeline.factories.writer import ProgramWriter


def cell_shelf(w: ProgramWriter, rng: np.random.Generator) -> None:
    cols, rows = int(rng.integers(4, 7)), int(rng.integers(2, 6))  # >= 3 dividers: not only mirror pairs
    cell, depth = u(rng, 0.3, 0.4), u(rng, 0.3, 0.4)
    t, frame_t = 0.015, 0.04
    width = cols * cell + (cols - 1) * t + 2 * frame_t
    height = rows * cell + (rows - 1) * t + 2 * frame_t
    mat = kit.wood(w, rng)
    frame = w.part("frame", kit.carcass(w, width, depth, height, frame_t, through=True), mat)
    for c in range(1, cols):
        x = -width / 2 + frame_t + c * cell + (c - 0.5) * t
        w.part("divider", w.box((t, depth, height - 2 * frame_t), (x, 0.0, height / 2)), mat, parent=frame,
               twin="divider")
    for r in range(1, rows):  # one board per cell: the full-height dividers run between them
        z = frame_t + r * cell + (r - 0.5) * t
        for c in range(cols):
            x = -width / 2 + frame_t + c * (cell + t) + cell / 2
            w.part("board", w.box((cell, depth, t), (x, 0.0, z)), mat, parent=frame, twin="board")
    bins = kit.fabric(w, rng)
    for r in range(rows):
        for c in range(cols):
            if rng.random() < 0.3:
                x = -width / 2 + frame_t + c * (cell + t) + cell / 2
                z = frame_t + r * (cell + t)
                size = (cell - 0.02, depth - 0.04, cell - 0.03)
                bin_mesh = kit.open_top_tray(w, size, (x, -0.01, z + size[2] / 2), 0.006)
                w.part("storage_bin", bin_mesh, bins, parent=frame, twin="storage_bin")


def large_shelf(w: ProgramWriter, rng: np.random.Generator) -> None:
    bays, levels = int(rng.integers(2, 5)), int(rng.integers(4, 7))
    bay_w, depth, height = u(rng, 0.7, 1.0), u(rng, 0.4, 0.6), u(rng, 1.6, 2.2)
    post = 0.04
    steel, board_mat = kit.metal(w, rng), kit.wood(w, rng) if rng.random() < 0.5 else kit.metal(w, rng)
    width = bays * bay_w + post
    board_t = 0.02
    levels_z = [0.1 + (height - 0.1 - board_t) * i / (levels - 1) for i in range(levels)]
    base = w.part("bottom_board", w.box((width - 2 * post, depth - 2 * post, board_t),
                                        (0.0, 0.0, levels_z[0] + board_t / 2)), board_mat)
    for b in range(bays + 1):
        x = -width / 2 + post / 2 + b * bay_w
        for y in (-depth / 2 + post / 2, depth / 2 - post / 2):
            w.part("upright", w.box((post, post, height), (x, y, height / 2)), steel, parent=base, twin="upright")
    for z in levels_z[1:]:
        w.part("board", w.box((width - 2 * post, depth - 2 * post, board_t), (0.0, 0.0, z + board_t / 2)), board_mat,
               parent=base, twin="board")


def simple_bookcase(w: ProgramWriter, rng: np.random.Generator) -> None:
    width, depth, height = u(rng, 0.6, 1.0), u(rng, 0.25, 0.35), u(rng, 1.0, 2.0)
    t = 0.018
    mat, book_mat = kit.wood(w, rng), w.material("Other", "paper books")
    inner = width - 2 * t
    root = w.part("back_panel", w.box((inner, 0.006, height - 0.02), (0.0, depth / 2 - 0.003, height / 2)), mat)
    for x in (-width / 2 + t / 2, width / 2 - t / 2):
        w.part("side", w.box((t, depth, height), (x, 0.0, height / 2)), mat, parent=root, twin="side")
    # top, bottom and shelves are one board design
    w.part("top", w.box((inner, depth - 0.006, t), (0.0, -0.003, height - t / 2)), mat, parent=root, twin="shelf")
    w.part("bottom", w.box((inner, depth - 0.006, t), (0.0, -0.003, 0.05 + t / 2)), mat, parent=root, twin="shelf")
    n = max(2, int((height - 0.1) / u(rng, 0.3, 0.38)) - 1)
    levels = [0.05 + t + (height - 0.05 - 2 * t) * (i + 1) / (n + 1) for i in range(n)]
    shelf_ids = [w.part("shelf", w.box((inner, depth - 0.006, t), (0.0, -0.003, z)), mat, parent=root, twin="shelf")
                 for z in levels]
    book_h, book_w, book_d = u(rng, 0.18, 0.25), u(rng, 0.025, 0.04), depth * 0.75
    for shelf_id, z in zip(shelf_ids, levels):
        count = int(rng.integers(2, 7))
        x0 = -inner / 2 + 0.02 + u(rng, 0.0, 0.2)
        for k in range(count):
            x = x0 + k * (book_w + 0.003)
            book = w.box((book_w, book_d, book_h), (x + book_w / 2, -0.01, z + t / 2 + book_h / 2))
            w.part("book", book, book_mat, parent=shelf_id, twin="book")


def triangle_shelf(w: ProgramWriter, rng: np.random.Generator) -> None:
    side, height = u(rng, 0.25, 0.45), u(rng, 0.6, 1.6)
    levels = int(rng.integers(3, 6))
    t, post_r = 0.018, 0.012
    mat, post_mat = kit.wood(w, rng), kit.metal(w, rng)
    # a right-angled corner shelf: the corner at the back (+Y), the hypotenuse facing the viewer
    half = side / math.sqrt(2)
    profile = [(0.0, half), (-half, 0.0), (half, 0.0)]
    zs = [0.03 + (height - 0.06) * i / (levels - 1) for i in range(levels)]
    bottom = w.part("board", w.extrude(profile, t, (0.0, -half / 2, zs[0])), mat)
    # a post just outside each corner of the boards, touching it
    corners = np.array(profile) + (0.0, -half / 2)
    centre = corners.mean(axis=0)
    for corner in corners:
        out = (corner - centre) / np.linalg.norm(corner - centre)
        x, y = corner + out * post_r
        w.part("post", w.cylinder(post_r, height, (float(x), float(y), height / 2), segments=12), post_mat,
               parent=bottom, twin="post")
    for z in zs[1:]:
        w.part("board", w.extrude(profile, t, (0.0, -half / 2, z)), mat, parent=bottom, twin="board")
