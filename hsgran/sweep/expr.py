"""Arithmetic expressions of swept parameters, for the ``[set]`` table of a sweep file.

``"3.9 * sin(radians(angle))"`` turns a swept impact angle into a velocity component. The text
is parsed with :mod:`ast` and only numbers, strings, parameter names, ``+ - * / // % **``,
unary signs, lists and the functions of :data:`FUNCTIONS` are accepted: a sweep file cannot run
arbitrary code on the workers (nothing is ever passed to ``eval``).
"""

from __future__ import annotations

import ast
import math
import operator

from hsgran.errors import InputError, did_you_mean

#: Functions an expression may call (all of :mod:`math`'s usual ones, plus abs/min/max).
FUNCTIONS = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "asin": math.asin, "acos": math.acos,
    "atan": math.atan, "atan2": math.atan2, "radians": math.radians, "degrees": math.degrees,
    "sqrt": math.sqrt, "exp": math.exp, "log": math.log, "log10": math.log10, "hypot": math.hypot,
    "abs": abs, "min": min, "max": max,
}
#: Named constants an expression may use.
CONSTANTS = {"pi": math.pi, "e": math.e, "inf": math.inf}

_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv, ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod,
           ast.Pow: operator.pow}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}


def parse_expression(text: str, key: str) -> ast.Expression:
    """Parse ``text`` and check that it uses only what :func:`evaluate` accepts.

    Raises:
        InputError: syntax error or a forbidden construct, naming ``key``.
    """
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        raise InputError(f"not an expression: {text!r}", key) from None
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
                name = node.func.id if isinstance(node.func, ast.Name) else ast.unparse(node.func)
                raise InputError(f"unknown function '{name}'{did_you_mean(name, FUNCTIONS)} in "
                                 f"{text!r}; known: {', '.join(FUNCTIONS)}", key)
            if node.keywords:
                raise InputError(f"functions take positional arguments only, in {text!r}", key)
        elif not isinstance(node, (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Constant,
                                   ast.Name, ast.List, ast.Tuple, ast.Load, *_BINARY, *_UNARY)):
            raise InputError(f"'{ast.unparse(node)}' is not allowed in an expression "
                             f"(numbers, parameters, + - * / // % **, and functions only)", key)
    return tree


def names_used(tree: ast.Expression) -> set[str]:
    """Parameter names an expression reads (functions and constants excluded)."""
    calls = {id(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
    return {n.id for n in ast.walk(tree)
            if isinstance(n, ast.Name) and id(n) not in calls and n.id not in CONSTANTS}


def evaluate(tree: ast.Expression, params: dict, key: str):
    """Value of a parsed expression with the parameters ``params`` (name → value).

    Raises:
        InputError: unknown name or an arithmetic error (division by zero, domain error),
            naming ``key``.
    """
    def ev(node):
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant):
            return node.value
        if isinstance(node, ast.Name):
            if node.id in params:
                return params[node.id]
            if node.id in CONSTANTS:
                return CONSTANTS[node.id]
            raise InputError(f"unknown name '{node.id}'{did_you_mean(node.id, params)}; swept "
                             f"parameters: {', '.join(params) or 'none'}", key)
        if isinstance(node, (ast.List, ast.Tuple)):
            return [ev(e) for e in node.elts]
        if isinstance(node, ast.UnaryOp):
            return _UNARY[type(node.op)](ev(node.operand))
        if isinstance(node, ast.BinOp):
            return _BINARY[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.Call):
            return FUNCTIONS[node.func.id](*(ev(a) for a in node.args))
        raise InputError(f"'{ast.unparse(node)}' is not allowed in an expression", key)

    try:
        value = ev(tree)
    except InputError:
        raise
    except (ArithmeticError, ValueError, TypeError) as exc:
        raise InputError(f"cannot evaluate {ast.unparse(tree)!r} with "
                         f"{_show(params)}: {exc}", key) from None
    if isinstance(value, float) and math.isnan(value):
        raise InputError(f"{ast.unparse(tree)!r} is NaN with {_show(params)}", key)
    return value


def _show(params: dict) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in params.items()) or "no parameters"
