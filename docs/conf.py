"""Sphinx configuration of eulertop's documentation site.

Build (after ``pip install -e ".[docs]"``), from the repository's root::

    python -m sphinx -W -b html docs docs/_build/html

``-W`` turns every warning into an error: a broken link or cross-reference, a page left out of
every table of contents, a docstring that does not parse, and a notebook cell that raises
(``nb_execution_raise_on_error``). The four notebooks in ``notebooks/`` (``docs/notebooks`` is a
link to that folder) are executed at build time by myst-nb, in a temporary folder, with their
outputs cached by jupyter-cache in ``docs/_build/.jupyter_cache``: a rebuild runs only the
notebooks whose code changed. Mathematics is typeset by MathJax 3 served from the site itself
(``_static/mathjax``, copied there by ``sphinx-mathjax-offline``): no page loads anything from
another host. ``docs/tests/test_site.py`` checks the built pages in headless Chromium.
"""

from __future__ import annotations

from importlib.metadata import version as _version

project = "eulertop"
author = "the eulertop authors"
copyright = "the eulertop authors"
release = _version("eulertop")
version = release

extensions = [
    "myst_nb",  # Markdown pages (MyST) and notebooks, executed at build
    "sphinx.ext.autodoc",  # the API reference, from the docstrings
    "sphinx.ext.napoleon",  # numpydoc sections in those docstrings
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into the site: no CDN
]

exclude_patterns = [
    "_build",
    "tests",  # the site's own check, not a page
    "bench/summary.md",  # eulertop bench's full tables: the page speed.md renders the same text
    "report",  # the example class report, linked as a file
    "**/.ipynb_checkpoints",
]

# --- MyST ---------------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3  # "#the-boundaries"-style links to headings, as on a code host

# --- notebooks (myst-nb) ------------------------------------------------------------------
nb_execution_mode = "cache"  # run a notebook when its code changed, else take the cache
nb_execution_timeout = 300  # s per cell, as tests/test_notebooks.py allows
nb_execution_in_temp = True  # each runs in a fresh temporary folder, as in the tests
nb_execution_raise_on_error = True  # a cell that raises stops the build
nb_execution_show_tb = True  # and its traceback is printed

# --- API reference ------------------------------------------------------------------------
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the numpydoc sections say what each argument is, with units
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

# A cross-reference to eulertop's own code that names nothing is an error. One to an object that
# exists but is outside the curated reference (an internal module a docstring points to) is set
# as plain text (``_existing_object_as_text``). Names from outside (numpy, nbformat, the
# builtins, the words numpydoc puts in a type: "array_like", "optional") are left as plain text
# too, since the build reaches no other site.
OWN_PACKAGES = ("solver", "problems", "grader", "eulertop")
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", rf"(?!({'|'.join(OWN_PACKAGES)})\.).*"),
]


def _python_object(dotted: str) -> object | None:
    """The object ``dotted`` names (a module, or attributes of one), or None."""
    import importlib

    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for name in parts[cut:]:
            obj = getattr(obj, name, None)
            if obj is None:
                return None
        return obj
    return None


def _existing_object_as_text(app, env, node, contnode):
    """``missing-reference``: an object of eulertop's own that exists, shown as plain text."""
    target = node.get("reftarget", "")
    if node.get("refdomain") != "py" or not target.startswith(tuple(p + "." for p in
                                                                    OWN_PACKAGES)):
        return None
    return contnode if _python_object(target) is not None else None


def setup(app):
    app.connect("missing-reference", _existing_object_as_text)

# --- HTML ---------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"eulertop {release}"
html_static_path: list[str] = []
html_last_updated_fmt = None
html_copy_source = False
