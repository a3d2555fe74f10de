"""Instance-heavy shelving (paper §3.3): cell shelf, large shelf, simple bookcase, triangle shelf.

Every board, divider, upright and book is its own part, and copies of one design share a
twin key, so these objects carry many `instance` relations.
"""

from __future__ import annotations

import math

import numpy as np

from jax3dc.factories import kit
from jax3dc.factories.writer import ProgramWriter
from jax3dc.parameters import Chance as B, Choice as K, Count as C, Draws, Number as N, Schema

CELL_SHELF_CELLS = 30  # rows x columns at most (5 x 6)
BOOKCASE_SHELVES = 5  # shelves between top and bottom at most (2 m tall, 0.3 m apart)


CELL_SHELF = Schema("cell_shelf", (
    C("columns", 4, 6), C("rows", 2, 5), N("cell", 0.3, 0.4), N("depth", 0.3, 0.4), K("wood", kit.WOODS),
    K("bin_fabric", kit.FABRICS), B("bins", 0.3, slots=CELL_SHELF_CELLS)))  # bins[row * 6 + column]


def cell_shelf(w: ProgramWriter, p: Draws) -> None:
    cols, rows = p.count("columns"), p.count("rows")  # >= 3 dividers: not only mirror pairs
    cell, depth = p.number("cell"), p.number("depth")
    t, frame_t = 0.015, 0.04
    width = cols * cell + (cols - 1) * t + 2 * frame_t
    height = rows * cell + (rows - 1) * t + 2 * frame_t
    mat = kit.wood(w, p, "wood")
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
    bins = kit.fabric(w, p, "bin_fabric")
    for r in range(rows):
        for c in range(cols):
            if p.chance("bins", r * 6 + c):
                x = -width / 2 + frame_t + c * (cell + t) + cell / 2
                z = frame_t + r * (cell + t)
                size = (cell - 0.02, depth - 0.04, cell - 0.03)
                bin_mesh = kit.open_top_tray(w, size, (x, -0.01, z + size[2] / 2), 0.006)
                w.part("storage_bin", bin_mesh, bins, parent=frame, twin="storage_bin")


LARGE_SHELF = Schema("large_shelf", (
    C("bays", 2, 4), C("levels", 4, 6), N("bay_width", 0.7, 1.0), N("depth", 0.4, 0.6), N("height", 1.6, 2.2),
    K("upright_metal", kit.METALS), B("wooden_boards", 0.5), K("board_wood", kit.WOODS), K("board_metal", kit.METALS)))


def large_shelf(w: ProgramWriter, p: Draws) -> None:
    bays, levels = p.count("bays"), p.count("levels")
    bay_w, depth, height = p.number("bay_width"), p.number("depth"), p.number("height")
    post = 0.04
    steel, board_mat = kit.metal(w, p, "upright_metal"), (kit.wood(w, p, "board_wood") if p.chance("wooden_boards") else
                                                          kit.metal(w, p, "board_metal"))
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


SIMPLE_BOOKCASE = Schema("simple_bookcase", (
    N("width", 0.6, 1.0), N("depth", 0.25, 0.35), N("height", 1.0, 2.0), K("wood", kit.WOODS),
    N("shelf_spacing", 0.3, 0.38), N("book_height", 0.18, 0.25), N("book_width", 0.025, 0.04),
    C("books", 2, 6, slots=BOOKCASE_SHELVES), N("book_offset", 0.0, 0.2, slots=BOOKCASE_SHELVES)))


def simple_bookcase(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    t = 0.018
    mat, book_mat = kit.wood(w, p, "wood"), w.material("Other", "paper books")
    inner = width - 2 * t
    root = w.part("back_panel", w.box((inner, 0.006, height - 0.02), (0.0, depth / 2 - 0.003, height / 2)), mat)
    for x in (-width / 2 + t / 2, width / 2 - t / 2):
        w.part("side", w.box((t, depth, height), (x, 0.0, height / 2)), mat, parent=root, twin="side")
    # top, bottom and shelves are one board design
    w.part("top", w.box((inner, depth - 0.006, t), (0.0, -0.003, height - t / 2)), mat, parent=root, twin="shelf")
    w.part("bottom", w.box((inner, depth - 0.006, t), (0.0, -0.003, 0.05 + t / 2)), mat, parent=root, twin="shelf")
    n = max(2, int((height - 0.1) / p.number("shelf_spacing")) - 1)
    levels = [0.05 + t + (height - 0.05 - 2 * t) * (i + 1) / (n + 1) for i in range(n)]
    shelf_ids = [w.part("shelf", w.box((inner, depth - 0.006, t), (0.0, -0.003, z)), mat, parent=root, twin="shelf")
                 for z in levels]
    book_h, book_w, book_d = p.number("book_height"), p.number("book_width"), depth * 0.75
    for i, (shelf_id, z) in enumerate(zip(shelf_ids, levels)):
        count = p.count("books", i)
        x0 = -inner / 2 + 0.02 + p.number("book_offset", i)
        for k in range(count):
            x = x0 + k * (book_w + 0.003)
            book = w.box((book_w, book_d, book_h), (x + book_w / 2, -0.01, z + t / 2 + book_h / 2))
            w.part("book", book, book_mat, parent=shelf_id, twin="book")


TRIANGLE_SHELF = Schema("triangle_shelf", (
    N("side", 0.25, 0.45), N("height", 0.6, 1.6), C("levels", 3, 5), K("wood", kit.WOODS), K("post_metal", kit.METALS)))


def triangle_shelf(w: ProgramWriter, p: Draws) -> None:
    side, height = p.number("side"), p.number("height")
    levels = p.count("levels")
    t, post_r = 0.018, 0.012
    mat, post_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "post_metal")
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
