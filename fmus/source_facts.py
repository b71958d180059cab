"""What the build reads off our modules' sources: top-level classes and relative imports,
parsed with :mod:`ast` (nothing imported), once per content and process.

The FMU registry (``FMUS``: which module defines ``class <Name>(Model)``) and the build's
staleness check (the modules an FMU packs) read every component module: ~0.1 s of each
``agilesat run`` (docs/fast_paths.md measures it; a cache on disk that saved it was not
worth its code).
"""

from __future__ import annotations

import ast
import functools


@functools.cache
def facts(source: str, filename: str) -> dict:
    """{"classes": [[name, [base names]], ...] (top-level classes), "imports": [[level,
    module, [names]], ...] (relative ``from … import``)} of a module's source."""
    tree = ast.parse(source, filename)
    return {
        "classes": [
            [node.name, [base.id for base in node.bases if isinstance(base, ast.Name)]]
            for node in tree.body
            if isinstance(node, ast.ClassDef)
        ],
        "imports": [
            [node.level, node.module, [alias.name for alias in node.names]]
            for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) and node.level
        ],
    }
