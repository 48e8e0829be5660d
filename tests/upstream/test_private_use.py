"""Stone Soup's private attributes are touched in one module of ctxmodels only,
``ctxmodels/_upstream.py`` (which lists each and why; ``test_internals.py`` checks
them against the installed Stone Soup).

A walk over the syntax trees of python/ctxmodels, every module but ``_upstream.py``:

* an attribute ``x._name`` (one leading underscore) whose name Stone Soup defines (a method,
  class attribute or instance attribute in the installed Stone Soup's source) and ctxmodels
  does not, or that ``_upstream.PRIVATE_NAMES`` lists, is a use of a Stone Soup private
  attribute;
* a name both define is ctxmodels' own only when :data:`OWN_ALSO_IN_STONESOUP` says so (a
  reviewed list: a new shared name fails until someone has looked at what it is read on);
* a private name neither defines must be one of :data:`OTHER_LIBRARIES`;
* a string or keyword starting ``_property_`` (a Property's slot, also in an f-string, or
  ``__dict__.update(_property_x=...)``) and a
  ``getattr``/``setattr``/``hasattr``/``delattr`` of a Stone Soup private name count as uses.

It approximates: an attribute is judged by its name, not by the type of the object it is
read on (hence the reviewed list).
"""
from __future__ import annotations

import ast
import pathlib

import pytest
import stonesoup

from ctxmodels import _upstream

ROOT = pathlib.Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "python" / "ctxmodels"
UPSTREAM_MODULE = PACKAGE / "_upstream.py"
STONESOUP = pathlib.Path(stonesoup.__file__).resolve().parent

#: Private names that ctxmodels and Stone Soup both define, each checked to be read here on
#: ctxmodels' own objects only (its own classes, or its attributes of its subclasses).
OWN_ALSO_IN_STONESOUP = frozenset({
    "_add",           # ArrayMultiMeasurementInitiator's own method
    "_hypothesiser",  # ArrayJPDATracker's own method
    "_log",           # NavigationTrack's own method (its navigation log)
    "_timestamp",     # ArrayPointProcessTracker's own method (core time -> datetime)
    "_track",         # Births' own track factory (Stone Soup's is its single-target trackers')
})

#: Private names of other libraries' public API (namedtuple methods).
OTHER_LIBRARIES = frozenset({"_asdict", "_fields", "_replace", "_make"})

_ATTRIBUTE_CALLS = {"getattr", "setattr", "hasattr", "delattr"}


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _sources(folder: pathlib.Path, skip=()) -> dict[pathlib.Path, ast.Module]:
    return {path: ast.parse(path.read_text(encoding="utf-8"))
            for path in sorted(folder.rglob("*.py"))
            if path not in skip and "tests" not in path.relative_to(folder).parts}


def _attribute_call(node: ast.Call) -> str | None:
    """The constant attribute name of ``getattr(x, "name")`` and its kin (``object.__setattr__``
    too), else None."""
    func = node.func
    name = func.id if isinstance(func, ast.Name) else func.attr if isinstance(
        func, ast.Attribute) else None
    if name in _ATTRIBUTE_CALLS or name in ("__setattr__", "__getattribute__", "__delattr__"):
        for arg in node.args[1:2]:
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                return arg.value
    return None


def defined_names(trees) -> set[str]:
    """The private names some code in ``trees`` defines: functions and classes, names and
    attributes assigned (also as ``__dict__`` keys), names imported, ``__slots__`` entries,
    attributes set with ``setattr``."""
    names = set()
    for tree in trees:
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                names.add(node.name)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                names.add(node.id)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                names.add(node.attr)
            elif isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store) \
                    and isinstance(node.value, ast.Attribute) and node.value.attr == "__dict__" \
                    and isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, str):
                names.add(node.slice.value)
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                names.update((alias.asname or alias.name).split(".")[0] for alias in node.names)
            elif isinstance(node, ast.Assign) and any(
                    isinstance(t, ast.Name) and t.id == "__slots__" for t in node.targets):
                names.update(c.value for c in ast.walk(node.value)
                             if isinstance(c, ast.Constant) and isinstance(c.value, str))
            elif isinstance(node, ast.Call) and _attribute_call(node) is not None \
                    and getattr(node.func, "id", getattr(node.func, "attr", "")) in (
                        "setattr", "__setattr__"):
                names.add(_attribute_call(node))
    return {name for name in names if _private(name)}


def private_uses(tree: ast.Module, ours: set[str], theirs: set[str],
                 own_also_theirs=OWN_ALSO_IN_STONESOUP) -> list[tuple[int, str]]:
    """(line, what) for each use of a Stone Soup private attribute in ``tree``, given the
    private names ctxmodels (``ours``) and Stone Soup (``theirs``) define."""
    found = []

    def judge(line: int, name: str, how: str):
        if name in _upstream.PRIVATE_NAMES or (name in theirs and name not in ours):
            found.append((line, f"{how} {name}: Stone Soup's (go through ctxmodels._upstream)"))
        elif name in theirs and name not in own_also_theirs:
            found.append((line, f"{how} {name}: defined by Stone Soup and by ctxmodels; "
                                "if ctxmodels' own here, list it in OWN_ALSO_IN_STONESOUP"))
        elif name not in theirs and name not in ours and name not in OTHER_LIBRARIES:
            found.append((line, f"{how} {name}: whose? (neither ctxmodels nor Stone Soup "
                                "defines it)"))

    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private(node.attr):
            judge(node.lineno, node.attr, "attribute")
        elif isinstance(node, ast.Call):
            name = _attribute_call(node)
            if name is not None and _private(name) and (
                    name in _upstream.PRIVATE_NAMES or (name in theirs and name not in ours)):
                judge(node.lineno, name, "attribute by name")
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) \
                and node.value.startswith("_property_"):
            found.append((node.lineno, f"slot name {node.value!r} (use _upstream.property_slot)"))
        elif isinstance(node, ast.keyword) and (node.arg or "").startswith("_property_"):
            found.append((node.value.lineno, f"slot name {node.arg} as a keyword (use "
                                             "_upstream.property_slot)"))
    return found


@pytest.fixture(scope="module")
def names():
    ours = defined_names(_sources(PACKAGE, skip={UPSTREAM_MODULE}).values())
    theirs = defined_names(_sources(STONESOUP).values())
    return ours, theirs


def test_no_stone_soup_private_attribute_outside_upstream(names):
    ours, theirs = names
    found = [f"{path.relative_to(ROOT)}:{line}: {what}"
             for path, tree in _sources(PACKAGE, skip={UPSTREAM_MODULE}).items()
             for line, what in private_uses(tree, ours, theirs)]
    assert found == [], "\n".join(found)


def test_upstream_reaches_what_it_lists(names):
    """Every name of ``_upstream.PRIVATE_NAMES`` is Stone Soup's and read in ``_upstream.py``;
    the reviewed shared names are not among them."""
    _, theirs = names
    tree = ast.parse(UPSTREAM_MODULE.read_text(encoding="utf-8"))
    read = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)}
    assert _upstream.PRIVATE_NAMES <= read
    assert _upstream.PRIVATE_NAMES <= theirs
    assert not _upstream.PRIVATE_NAMES & OWN_ALSO_IN_STONESOUP


def test_the_walk_finds_private_uses(names):
    """The check can fail: each kind of use in a made-up module is found."""
    ours, theirs = names
    source = '''
model = updater._check_measurement_model(raw)
live = tracker._tracks
hypothesis.__dict__["_property_single_hypotheses"] = value
key = f"_property_{name}"
getter = getattr(prop, "_getter")
pose.__dict__.update(_property_x=x)
'''
    found = private_uses(ast.parse(source), ours, theirs)
    assert sorted(line for line, _ in found) == [2, 3, 4, 5, 6, 7], found
    # a name both define is flagged until reviewed
    shared = sorted((ours & theirs) - _upstream.PRIVATE_NAMES)
    if shared:
        tree = ast.parse(f"x.{shared[0]}")
        assert private_uses(tree, ours, theirs, own_also_theirs=frozenset()) != []
    assert private_uses(ast.parse("x._no_such_private_name"), ours, theirs) != []
    assert private_uses(ast.parse("row._asdict()\nself._core"), ours, theirs) == []
