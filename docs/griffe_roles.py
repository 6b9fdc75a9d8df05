"""Griffe extension for the API reference: Sphinx cross-reference roles -> mkdocstrings links.

cmpsim's docstrings use Sphinx roles (``:func:`solve```, ``:class:`~cmpsim.inputs.config.Config```,
``:meth:`Config.default```), which Markdown would print literally. Once the package is
loaded, this extension rewrites each role in every docstring:

* into a cross-reference ``[`name`][cmpsim.module.name]`` when the name resolves, from the
  object's own scope outwards (class, module, package), to a public, documented cmpsim object
  (one that the API page renders); mkdocs-autorefs then checks the link, so a broken one fails the strict build;
* into plain code (``name``) otherwise (private helpers, third-party names such as
  ``xarray.Dataset``).

``~a.b.c`` shows ``c``, as in Sphinx. The reST literal-block marker (``Example::`` at the end
of a line) becomes a single colon; the indented block after it is a Markdown code block
already. Used by mkdocs.yml (mkdocstrings ``extensions``).
"""

from __future__ import annotations

import re
from typing import Any

from griffe import Alias, Extension, Module, Object

LITERAL_MARKER = re.compile(r"(?<=\S)::[ \t]*$", re.M)  # reST "Example::" before a literal block
ROLE = re.compile(r":(?:py:)?(?:func|class|meth|data|attr|mod|exc|obj|const):`(~?)([^`<>]+?)`")


def _lookup(scope: Object, name: str) -> Object | None:
    try:
        found = scope[name]
    except Exception:
        return None
    if isinstance(found, Alias):
        try:
            found = found.final_target
        except Exception:
            return None
    return found


def _is_documented(obj: Object) -> bool:
    """Public all the way up and documented (so the API page renders it, given its options)."""
    if not obj.has_docstrings:
        return False
    node: Any = obj
    while node is not None:
        if not getattr(node, "is_public", True):
            return False
        node = node.parent
    return obj.path.startswith("cmpsim")


class SphinxRoles(Extension):
    """Rewrite Sphinx roles in the docstrings of the loaded package."""

    def on_package(self, *, pkg: Module, **kwargs: Any) -> None:
        if pkg.name != "cmpsim":
            return
        root = pkg
        seen: set[str] = set()

        def resolve(context: Object, name: str) -> Object | None:
            name = name.strip().rstrip("()")
            if name.startswith("cmpsim."):
                return _lookup(root, name[len("cmpsim.") :])
            scope: Any = context
            while scope is not None:
                hit = _lookup(scope, name)
                if hit is not None:
                    return hit
                scope = scope.parent
            return None

        def rewrite(obj: Object) -> None:
            if obj.docstring is None:
                return

            def repl(m: re.Match) -> str:
                tilde, name = m.group(1), m.group(2).strip()
                shown = name.split(".")[-1] if tilde else name
                target = resolve(obj, name)
                if target is not None and _is_documented(target):
                    return f"[`{shown}`][{target.path}]"
                return f"`{shown}`"

            obj.docstring.value = LITERAL_MARKER.sub(":", ROLE.sub(repl, obj.docstring.value))

        def walk(obj: Object) -> None:
            if obj.path in seen:
                return
            seen.add(obj.path)
            rewrite(obj)
            for member in list(obj.members.values()):
                if isinstance(member, Alias):
                    continue
                walk(member)

        walk(root)
