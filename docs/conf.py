"""Sphinx configuration of eomgen's documentation (bash scripts/docs.sh).

Sphinx rather than MkDocs: autodoc + napoleon read the numpy-style
docstrings of the package as they are, the C domain documents the generated
C interface (rendered from gen/codegen/abi.py by _ext/eomgen_capi.py), and
sphinx-gallery runs every tutorial at build time and keeps its figures.
Theme: furo (readable code blocks and tables, a sidebar that holds the
guides and the API, light and dark); alabaster's fixed narrow column cuts
the C prototypes and the wide tables of the guides.
"""
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))               # gen, and examples/ as a package
sys.path.insert(0, str(ROOT / "examples"))  # examples import each other by name
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import gen  # noqa: E402

project = "eomgen"
author = "eomgen developers"
copyright = "eomgen developers"
release = version = gen.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "myst_parser",
    "eomgen_capi",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "tutorials", "screenshots", "**/sg_execution_times.rst",
                    "sg_execution_times.rst"]
templates_path = []

# -- autodoc / napoleon: numpy-style docstrings, signatures without type hints
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_param = True
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autodoc_class_signature = "separated"
add_module_names = False

# -- MyST (the topic guides are Markdown, as the README was)
myst_enable_extensions = ["colon_fence", "dollarmath"]
myst_heading_anchors = 3

# -- sphinx-gallery: every tutorial is a script executed at build time; its
# assertions check its numbers against the reference, a failure fails the build
sphinx_gallery_conf = {
    "examples_dirs": ["tutorials"],
    "gallery_dirs": ["auto_tutorials"],
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "remove_config_comments": True,
    "show_memory": False,
    "min_reported_time": 1,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "write_computation_times": False,
}

# -- HTML
html_theme = "furo"
html_title = f"eomgen {release}"
html_static_path = []
html_theme_options = {"navigation_with_keys": True}
pygments_style = "sphinx"
