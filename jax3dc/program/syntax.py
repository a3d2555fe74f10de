"""Static check of part-program text: which Python syntax the language accepts.

A program is Python syntax, parsed with `ast` and never executed by Python. Accepted:
  * `name = <expr>` (one plain name; not a predefined function's name, no dunder names),
  * `<call>` as a statement (usually `part(...)`),
  * `for name in range(...)` with 1-3 arguments and a body of accepted statements
    (the interpreter caps the total number of executed statements),
  * expressions: int/float/str literals, tuples and lists, unary +/-, binary + - * /,
    names bound earlier, and calls of predefined functions with positional and keyword
    arguments (no *args / **kwargs).
Everything else is rejected with a `ProgramError` naming the line.
"""

from __future__ import annotations

import ast
import inspect

from jax3dc.errors import ProgramError
from jax3dc.program.library import FUNCTIONS

MAX_PROGRAM_CHARS = 1_000_000

_FORBIDDEN = {
    ast.Import: "imports are not allowed",
    ast.ImportFrom: "imports are not allowed",
    ast.Attribute: "attribute access (a.b) is not allowed",
    ast.Subscript: "subscripts (a[i]) are not supported",
    ast.Lambda: "lambda is not allowed",
    ast.ListComp: "comprehensions are not allowed",
    ast.SetComp: "comprehensions are not allowed",
    ast.DictComp: "comprehensions are not allowed",
    ast.GeneratorExp: "generator expressions are not allowed",
    ast.FunctionDef: "function definitions (def) are not allowed",
    ast.AsyncFunctionDef: "function definitions (def) are not allowed",
    ast.ClassDef: "class definitions are not allowed",
    ast.While: "while loops are not allowed; use `for i in range(n)`",
    ast.If: "if statements are not supported",
    ast.With: "with statements are not allowed",
    ast.Try: "try statements are not allowed",
    ast.Global: "global is not allowed",
    ast.Nonlocal: "nonlocal is not allowed",
    ast.Delete: "del is not allowed",
    ast.AugAssign: "augmented assignment (+=) is not supported; write `x = x + 1`",
    ast.AnnAssign: "annotated assignment is not supported",
    ast.Return: "return is not allowed outside a function",
    ast.Dict: "dictionaries are not supported",
    ast.Set: "sets are not supported",
    ast.JoinedStr: "f-strings are not supported",
    ast.Compare: "comparisons are not supported",
    ast.BoolOp: "boolean operators are not supported",
    ast.IfExp: "conditional expressions are not supported",
    ast.NamedExpr: ":= is not allowed",
    ast.Starred: "*args / unpacking is not allowed",
    ast.Await: "await is not allowed",
    ast.Yield: "yield is not allowed",
    ast.YieldFrom: "yield is not allowed",
}

SIGNATURES = {name: inspect.signature(fn) for name, fn in FUNCTIONS.items()}
ALLOWED_BINOPS = (ast.Add, ast.Sub, ast.Mult, ast.Div)
ALLOWED_UNARY = (ast.USub, ast.UAdd)


def _line(node: ast.AST) -> int | None:
    return getattr(node, "lineno", None)


def _reject(node: ast.AST) -> ProgramError:
    message = _FORBIDDEN.get(type(node), f"{type(node).__name__} is not allowed in a part program")
    return ProgramError(_line(node), message)


def _check_name(name: str, node: ast.AST) -> None:
    if "__" in name:
        raise ProgramError(_line(node), f"dunder names such as {name!r} are not allowed")


class _Checker:
    def __init__(self) -> None:
        self.bound: set[str] = set()

    def statements(self, body: list[ast.stmt]) -> None:
        for stmt in body:
            self.statement(stmt)

    def statement(self, stmt: ast.stmt) -> None:
        if isinstance(stmt, ast.Assign):
            if len(stmt.targets) != 1 or not isinstance(stmt.targets[0], ast.Name):
                raise ProgramError(stmt.lineno, "assign to one plain name (a = ...)")
            self.expression(stmt.value)
            self.bind(stmt.targets[0])
        elif isinstance(stmt, ast.Expr):
            if not isinstance(stmt.value, ast.Call):
                self.expression(stmt.value)  # a forbidden construct gets its own message first
                raise ProgramError(stmt.lineno, "a statement must be an assignment or a call such as part(...)")
            self.expression(stmt.value)
        elif isinstance(stmt, ast.For):
            self.loop(stmt)
        elif isinstance(stmt, ast.Pass):
            return
        else:
            raise _reject(stmt)

    def loop(self, stmt: ast.For) -> None:
        if not isinstance(stmt.target, ast.Name):
            raise ProgramError(stmt.lineno, "the loop variable must be one plain name")
        it = stmt.iter
        if not (isinstance(it, ast.Call) and isinstance(it.func, ast.Name) and it.func.id == "range"):
            raise ProgramError(stmt.lineno, "only `for name in range(...)` loops are allowed")
        if it.keywords or not 1 <= len(it.args) <= 3:
            raise ProgramError(stmt.lineno, "range takes 1 to 3 positional arguments")
        for arg in it.args:
            self.expression(arg)
        if stmt.orelse:
            raise ProgramError(stmt.lineno, "for ... else is not allowed")
        self.bind(stmt.target)
        self.statements(stmt.body)

    def bind(self, target: ast.Name) -> None:
        _check_name(target.id, target)
        if target.id in FUNCTIONS or target.id == "range":
            raise ProgramError(target.lineno, f"cannot assign to the predefined name {target.id!r}")
        self.bound.add(target.id)

    def expression(self, node: ast.expr) -> None:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float, str)):
                raise ProgramError(node.lineno, f"literal {node.value!r:.60} is not supported (numbers and text only)")
            if isinstance(node.value, str) and not node.value.isascii():
                try:
                    node.value.encode("utf-8")
                except UnicodeEncodeError as exc:  # "\ud800": a lone surrogate cannot be printed or written
                    raise ProgramError(node.lineno, f"text is not valid Unicode (a lone surrogate at character "
                                                    f"{exc.start})") from None
        elif isinstance(node, (ast.Tuple, ast.List)):
            for elt in node.elts:
                self.expression(elt)
        elif isinstance(node, ast.UnaryOp):
            if not isinstance(node.op, ALLOWED_UNARY):
                raise ProgramError(node.lineno, "only unary + and - are allowed")
            self.expression(node.operand)
        elif isinstance(node, ast.BinOp):
            if not isinstance(node.op, ALLOWED_BINOPS):
                raise ProgramError(node.lineno, "only + - * / are allowed")
            self.expression(node.left)
            self.expression(node.right)
        elif isinstance(node, ast.Name):
            _check_name(node.id, node)
            if node.id in FUNCTIONS or node.id == "range":
                raise ProgramError(node.lineno, f"{node.id!r} is a function; call it with (...)")
            if node.id not in self.bound:
                raise ProgramError(node.lineno, f"unknown name {node.id!r} (not bound earlier in the program)")
        elif isinstance(node, ast.Call):
            self.call(node)
        else:
            raise _reject(node)

    def call(self, node: ast.Call) -> None:
        if not isinstance(node.func, ast.Name):
            raise _reject(node.func) if isinstance(node.func, ast.Attribute) else ProgramError(
                node.lineno, "only predefined functions can be called")
        name = node.func.id
        _check_name(name, node.func)
        if name not in FUNCTIONS:
            raise ProgramError(node.lineno, f"{name!r} is not a predefined function")
        for arg in node.args:
            if isinstance(arg, ast.Starred):
                raise _reject(arg)
            self.expression(arg)
        for kw in node.keywords:
            if kw.arg is None:
                raise ProgramError(node.lineno, "**kwargs is not allowed")
            _check_name(kw.arg, node)
            self.expression(kw.value)
        try:
            SIGNATURES[name].bind(*node.args, **{kw.arg: kw.value for kw in node.keywords})
        except TypeError as exc:
            raise ProgramError(node.lineno, f"{name}(): {exc}") from None


def parse_program(text: str) -> ast.Module:
    """Parse and check a part program; raises ProgramError naming the offending line."""
    if not isinstance(text, str):
        raise ProgramError(None, "a part program must be text")
    if len(text) > MAX_PROGRAM_CHARS:
        raise ProgramError(None, f"the program is longer than {MAX_PROGRAM_CHARS} characters")
    try:
        tree = ast.parse(text, mode="exec")
        _Checker().statements(tree.body)
    except SyntaxError as exc:
        raise ProgramError(exc.lineno, f"syntax error: {exc.msg}") from None
    except ValueError as exc:  # e.g. NUL bytes
        raise ProgramError(None, f"unreadable program: {exc}") from None
    except (RecursionError, MemoryError):
        raise ProgramError(None, "the program is nested too deeply") from None
    return tree
