"""Imports flow one way: a module never imports from a higher layer (docs/architecture.md §1)."""

import ast
import re
from pathlib import Path

import hsgran

PACKAGE = Path(hsgran.__file__).parent

#: Layer of every module (dotted name below ``hsgran``, or a subpackage prefix ending in ".").
LAYERS = {
    "__init__": 0,
    "errors": 0,
    "system": 0,
    "_jit": 0,
    "effects": 1,
    "materials": 1,
    "refdata": 1,
    "data": 0,
    "_loop": 5,
    "_state": 5,
    "_flight": 5,
    "_predict": 5,
    "_settling": 5,
    "_cluster": 5,
    "_observe": 5,
    "_cylinder": 5,
    "_riding": 5,
    "contact.": 2,
    "motion": 2,
    "wallmotion": 2,
    "wallspec": 1,
    "onplane": 2,
    "outlets": 2,
    "facets": 2,
    "shapes": 1,
    "_exchange": 5,
    "events.": 3,
    "events.kinds": 3,
    "impact": 4,
    "scene": 4,
    "placement": 4,
    "inflow": 4,
    "overrides": 4,
    "engine": 5,
    "reference": 5,
    "dem.": 5,
    "io.": 5,
    "render": 6,
    "animation": 6,
    "plot": 6,
    "export": 6,
    "fields": 6,
    "observables": 6,
    "validate": 6,
    "validation.": 6,
    "cli": 6,
    "precompile": 6,
    "api": 6,
    "sweep.": 6,
    "__main__": 6,
}


def layer_of(module: str) -> int:
    """Layer of a module given as dotted name relative to ``hsgran``."""
    if module in LAYERS:
        return LAYERS[module]
    for prefix, layer in LAYERS.items():
        if prefix.endswith(".") and (module + ".").startswith(prefix):
            return layer
    raise AssertionError(f"hsgran.{module} has no layer: add it to LAYERS in tests/test_layers.py")


def modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__" and len(parts) > 1:
            parts = parts[:-1]
        yield ".".join(parts), path


def imported_hsgran_modules(path: Path):
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "hsgran":
                for alias in node.names:
                    yield alias.name
            elif node.module.startswith("hsgran."):
                yield node.module.removeprefix("hsgran.")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("hsgran."):
                    yield alias.name.removeprefix("hsgran.")


def test_every_module_has_a_layer():
    for name, _ in modules():
        layer_of(name)


def test_every_layer_entry_names_a_module():
    names = [name for name, _ in modules()]
    stale = [key for key in LAYERS
             if not (any((name + ".").startswith(key) for name in names) if key.endswith(".")
                     else key in names)]
    assert not stale, f"LAYERS entries that name no module of hsgran: {stale}"


def test_module_docstrings_state_their_own_layer():
    wrong = []
    for name, path in modules():
        doc = ast.get_docstring(ast.parse(path.read_text(), filename=str(path))) or ""
        for said in re.findall(r"\blayer (\d+)", doc, flags=re.IGNORECASE):
            if int(said) != layer_of(name):
                wrong.append(f"hsgran.{name} says layer {said}, LAYERS says {layer_of(name)}")
    assert not wrong, "\n".join(wrong)


def test_imports_flow_one_way():
    offenders = []
    for name, path in modules():
        own = layer_of(name)
        for target in imported_hsgran_modules(path):
            if target == "__version__":
                continue
            if layer_of(target) > own:
                offenders.append(f"hsgran.{name} (layer {own}) imports hsgran.{target} "
                                 f"(layer {layer_of(target)})")
    assert not offenders, "\n".join(offenders)


def test_heavy_optional_dependencies_are_not_imported_at_package_import():
    import subprocess
    import sys

    code = ("import sys, hsgran, hsgran.impact, hsgran.materials; "
            "print(','.join(m for m in ('pyvista', 'vtk', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""
