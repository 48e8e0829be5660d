"""Stone Soup YAML support for ctxmodels components.

Stone Soup's serialiser writes any :class:`~stonesoup.base.Base` as ``!module.Class``, but
reads back only tags under ``!stonesoup.``. Its ``stonesoup.serialise.yaml`` entry point
(declared in pyproject.toml) calls :func:`register` on every Stone Soup ``YAML`` instance,
which teaches it to read ``!ctxmodels.`` tags too.

A tag names the module that defines the class, which the package's layout may move; a tag
whose module no longer holds the class still loads when the class is a public name of the
package the tag is under (``!ctxmodels.stonesoup.<module>.PHDUpdater`` as
:class:`ctxmodels.stonesoup.PHDUpdater`, ``!ctxmodels.<module>.RangeBands`` as
:class:`ctxmodels.RangeBands`), so YAML files outlive a reorganisation of the modules.
"""
from __future__ import annotations

from importlib import import_module

from ruamel.yaml.constructor import ConstructorError
from stonesoup.base import Base


def _public_class(module_name: str, class_name: str):
    """The public ``class_name`` of the package ``module_name`` is under (``ctxmodels`` or
    ``ctxmodels.stonesoup``), or None."""
    package = "ctxmodels.stonesoup" if module_name.startswith("ctxmodels.stonesoup.") \
        else "ctxmodels"
    public = import_module(package)
    return getattr(public, class_name) if class_name in public.__all__ else None


def _component_class(tag_suffix: str, node):
    module_name, _, class_name = f"ctxmodels.{tag_suffix}".rpartition(".")
    try:
        class_ = getattr(import_module(module_name), class_name)
    except (ImportError, AttributeError):
        class_ = _public_class(module_name, class_name)
    if class_ is None:
        raise ConstructorError("while constructing a ctxmodels component", node.start_mark,
                               f"unable to import 'ctxmodels.{tag_suffix}'", node.start_mark)
    if not (isinstance(class_, type) and issubclass(class_, Base)):
        raise ConstructorError("while constructing a ctxmodels component", node.start_mark,
                               f"'ctxmodels.{tag_suffix}' is not a component", node.start_mark)
    return class_


def _component_from_yaml(constructor, tag_suffix, node):
    class_ = _component_class(tag_suffix, node)
    constructor.deep_construct = True  # sub-components must be complete before __init__
    properties = list(constructor.construct_yaml_omap(node))[0]
    try:
        return class_(**properties)
    except Exception as err:
        raise ConstructorError("while constructing a ctxmodels component", node.start_mark,
                               str(err), node.start_mark) from err


def register(yaml) -> None:
    """Entry point for ``stonesoup.serialise.yaml``."""
    yaml.constructor.add_multi_constructor("!ctxmodels.", _component_from_yaml)
