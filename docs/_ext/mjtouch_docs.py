"""Pages generated from the code at build time, so they cannot drift:

- ``mjtouch-attribute-table``: the plugin's attribute table, from the table the
  plugin parses with (plugin/core/pipeline/attributes.cc, through
  ``mjtouch._core.attribute_table_markdown``, as .ci/attribute_table.py);
- ``mjtouch-cli``: every command's ``--help``, from the CLI's argparse parser;
- docstrings written in Markdown (fenced code, tables) turned into reST for
  autodoc.
"""

from __future__ import annotations

import argparse
import re

from docutils import nodes
from sphinx.util.docutils import SphinxDirective


class AttributeTable(SphinxDirective):
    """The attribute table, parsed as Markdown into this page."""

    def run(self):
        from mjtouch import _core

        text = _core.attribute_table_markdown()
        # MyST parses the table as if written in the page.
        return self.parse_text_to_nodes(text)


class _Captured(Exception):
    def __init__(self, parser):
        self.parser = parser


def cli_parser() -> argparse.ArgumentParser:
    """The CLI's top parser, as ``mjtouch.cli.main`` builds it (captured at
    ``parse_args``, so this works however the CLI assembles it)."""
    from mjtouch import cli

    original = argparse.ArgumentParser.parse_args

    def capture(self, *args, **kwargs):
        raise _Captured(self)

    argparse.ArgumentParser.parse_args = capture
    try:
        cli.main([])
    except _Captured as c:
        return c.parser
    finally:
        argparse.ArgumentParser.parse_args = original
    raise RuntimeError("mjtouch.cli.main did not parse arguments")


def subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


class CliReference(SphinxDirective):
    """``mjtouch --help`` and each command's ``--help``, as the user sees them."""

    def run(self):
        parser = cli_parser()
        out = []
        sections = [("mjtouch", parser)] + [
            (f"mjtouch {name}", p) for name, p in subcommands(parser).items()
        ]
        for title, p in sections:
            section = nodes.section(ids=[nodes.make_id(title)])
            section += nodes.title(text=title)
            help_text = p.format_help()
            block = nodes.literal_block(help_text, help_text)
            block["language"] = "text"
            section += block
            out.append(section)
        return out


_FENCE = re.compile(r"^(\s*)```(\w*)\s*$")
_LIST_ITEM = re.compile(r"^(\s*)([-*]|\d+\.) \S")
_LONE_STAR = re.compile(r"(?<=[\w)])\*(?![\w*])")  # F*, (p)*: a mark, not emphasis
_BARE_STAR = re.compile(r"(?<![\w*\\])\*(?=[:\s])")  # "*: full scale"


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _table(rows: list[str], indent: str) -> list[str]:
    """A Markdown pipe table as a reST list-table."""
    cells = [
        [c.strip() for c in r.strip().strip("|").split("|")]
        for r in rows
        if not set(r.replace("|", "").strip()) <= set("-: ")
    ]
    out = [f"{indent}.. list-table::", f"{indent}   :header-rows: 1", ""]
    for row in cells:
        row = [_LONE_STAR.sub(r"\\*", c) or " " for c in row]
        out.append(f"{indent}   * - {row[0]}")
        out += [f"{indent}     - {c}" for c in row[1:]]
    return out + [""]


def markdown_docstring(app, what, name, obj, options, lines: list[str]) -> None:
    """Docstrings here mix reST roles with Markdown habits; turn the Markdown
    into reST so autodoc renders it: fenced code, pipe tables, lists that
    start or end without a blank line, code indented under a paragraph (a
    Markdown code block), and ``|x|`` absolute values in prose."""
    out: list[str] = []
    i = 0
    list_indent = None  # content indent of the list being read
    while i < len(lines):
        line = lines[i]
        prev = out[-1] if out else ""
        m = _FENCE.match(line)
        if m:
            indent, lang = m.group(1), m.group(2) or "text"
            out += ["", f"{indent}.. code-block:: {lang}", ""]
            i += 1
            while i < len(lines) and not _FENCE.match(lines[i]):
                out.append(f"{indent}   {lines[i][len(indent) :]}" if lines[i].strip() else "")
                i += 1
            out.append("")
            i += 1
            continue
        stripped = line.strip()
        if stripped.startswith("|") and stripped.endswith("|") and stripped.count("|") > 2:
            indent = line[: _indent(line)]
            rows = []
            while (
                i < len(lines)
                and lines[i].strip().startswith("|")
                and lines[i].strip().endswith("|")
            ):
                rows.append(lines[i])
                i += 1
            out += ([""] if prev.strip() else []) + _table(rows, indent)
            continue
        # a Markdown code block: indented under a paragraph after a blank line
        if (
            stripped
            and not prev.strip()
            and len(out) >= 2
            and out[-2].strip()
            and _indent(line) >= _indent(out[-2]) + 4
            and list_indent is None
            and not out[-2].rstrip().endswith("::")
            and not _LIST_ITEM.match(out[-2])
            and not out[-2].lstrip().startswith("..")
        ):
            base = _indent(line)
            out[-1:] = ["", f"{' ' * (base - 4)}::", ""]
            while i < len(lines) and (not lines[i].strip() or _indent(lines[i]) >= base):
                out.append(lines[i])
                i += 1
            out.append("")
            continue
        item = _LIST_ITEM.match(line)
        if item:
            if prev.strip() and list_indent is None:
                out.append("")  # a list right after a paragraph line
            list_indent = len(item.group(1)) + len(item.group(2)) + 1
        elif list_indent is not None and stripped and _indent(line) < list_indent:
            if prev.strip():
                out.append("")  # the list ends without a blank line
            list_indent = None
        elif not stripped:
            pass
        if "|" in line and not stripped.startswith("|"):
            line = re.sub(r"(?<!\\)\|", r"\\|", line)  # |x| is an absolute value
        if not item:
            line = _BARE_STAR.sub(r"\\*", line)
        out.append(line)
        i += 1
    lines[:] = out


def setup(app):
    app.add_directive("mjtouch-attribute-table", AttributeTable)
    app.add_directive("mjtouch-cli", CliReference)
    app.connect("autodoc-process-docstring", markdown_docstring)
    return {"version": "1", "parallel_read_safe": True}
