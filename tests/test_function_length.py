"""No function of hsgran is longer than MAX_FUNCTION_LINES unless it says why.

A function's length runs from its ``def`` line to its last line, docstring and comments
included. A longer one passes only with a ``# long: <reason>`` comment in the block of comment
lines just above it (above its decorators, if any) or between its ``def`` line and its first
statement.
"""

import ast
import re
from pathlib import Path

import hsgran

PACKAGE = Path(hsgran.__file__).parent

#: Most lines a function may have without saying why: a function of this size still fits on two
#: screens, so a reader can hold all of it in view while checking it.
MAX_FUNCTION_LINES = 150

LONG_REASON = re.compile(r"#\s*long:\s*\S")


def functions(tree):
    """(qualified name, node) of every function and method in ``tree``, nested ones included."""
    stack = [("", node) for node in tree.body]
    while stack:
        prefix, node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            name = prefix + node.name
            if not isinstance(node, ast.ClassDef):
                yield name, node
            stack.extend((name + ".", child) for child in node.body)
        else:
            stack.extend((prefix, child) for child in ast.iter_child_nodes(node))


def says_why(lines, node) -> bool:
    """Whether ``node`` carries a ``# long:`` comment above it or before its first statement."""
    top = min([node.lineno] + [d.lineno for d in node.decorator_list])
    above = top - 2  # 0-based index of the line just above
    while above >= 0 and lines[above].lstrip().startswith("#"):
        if LONG_REASON.match(lines[above].lstrip()):
            return True
        above -= 1
    return any(LONG_REASON.search(line) for line in lines[node.lineno:node.body[0].lineno])


def long_functions():
    """``module:qualified name`` → length of every over-long function without a reason."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        text = path.read_text()
        lines = text.splitlines()
        for name, node in functions(ast.parse(text, filename=str(path))):
            length = node.end_lineno - node.lineno + 1
            if length > MAX_FUNCTION_LINES and not says_why(lines, node):
                found[f"{module}:{name}"] = length
    return found


def test_functions_are_short_or_say_why():
    found = long_functions()
    offenders = sorted(f"{name} ({n} lines)" for name, n in found.items())
    assert not offenders, (
        f"functions longer than {MAX_FUNCTION_LINES} lines without a '# long: <reason>' "
        "comment: " + ", ".join(offenders))


def test_a_reason_above_the_decorators_or_before_the_first_statement_is_accepted():
    body = "    x = 1\n" * MAX_FUNCTION_LINES
    sources = {"bare": f"def f():\n{body}",
               "above": f"# long: why\n@njit\ndef f():\n{body}",
               "inside": f"def f(a,\n      b):\n    # long: why\n{body}",
               "no reason": f"# long:\ndef f():\n{body}"}
    verdict = {}
    for case, source in sources.items():
        (_, node), = functions(ast.parse(source))
        verdict[case] = says_why(source.splitlines(), node)
    assert verdict == {"bare": False, "above": True, "inside": True, "no reason": False}
