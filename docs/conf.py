"""Sphinx configuration: the guide pages (Markdown, MyST), the example gallery (every
example is executed during the build; a failing example fails it) and the API reference
(autodoc). Built by ``scripts/docs.sh`` with ``-W``: warnings are errors."""
import os
import warnings

import matplotlib

matplotlib.use("Agg")  # no display: the gallery's figures are rendered off-screen
# Examples' worker processes (the Dask LocalCluster, the process pool) start with this
# environment: no GUI backend there either.
os.environ.setdefault("MPLBACKEND", "Agg")

# The Monte Carlo example starts a Dask LocalCluster: its scheduler's INFO lines would fill
# the build log (only the log level of Dask's own logger; warnings still show).
os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "warning")

# A warning raised from ctxmodels' own code while the examples run fails the build, as it
# fails the tests (pyproject's filterwarnings); other packages' warnings stay warnings.
warnings.filterwarnings("error", module=r"ctxmodels(\.|$)")

# The installed package (editable in development and CI: scripts/test.sh), the one the
# examples run against.
import ctxmodels  # noqa: E402

project = "ctxmodels"
author = "ctxmodels contributors"
copyright = "ctxmodels contributors"
release = version = ctxmodels.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "myst_parser",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
# examples/ holds the gallery sources (GALLERY_HEADER.rst included); the gallery pages are
# generated into auto_examples/.
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "examples",
                    "results"]  # the confirmatory run's files, read on their own
templates_path: list[str] = []

# --- autodoc -------------------------------------------------------------------------------
autodoc_default_options = {
    "member-order": "bysource",
    "show-inheritance": True,
}
autodoc_typehints = "signature"
# Stone Soup components declare their parameters as ``Property`` class attributes; autodoc
# shows each one (with its ``doc``) as an attribute of the class it is declared on.
autodoc_inherit_docstrings = True
# The docstrings are NumPy-style where they have sections at all.
napoleon_google_docstring = False
napoleon_numpy_docstring = True

# --- MyST (the guide pages) ----------------------------------------------------------------
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3

# --- sphinx-gallery ------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/.*\.py",  # execute every example
    "plot_gallery": True,
    "abort_on_example_error": True,  # a failing example fails the build
    "only_warn_on_example_error": False,
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
}

# --- HTML ----------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"ctxmodels {release}"
html_static_path: list[str] = []
