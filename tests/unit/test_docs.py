"""The docs' generated pages come from the code, README stays a front page,
and the docstring converter turns Markdown into reST. (The strict Sphinx
build itself runs in .ci/run.)"""

from __future__ import annotations

import importlib.util
import pathlib
import re
import subprocess
import sys

from conftest import registered_attributes

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


def docs_ext():
    spec = importlib.util.spec_from_file_location("mjtouch_docs", DOCS / "_ext" / "mjtouch_docs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_attribute_page_is_generated_not_copied():
    page = (DOCS / "reference" / "attributes.md").read_text()
    assert "```{mjtouch-attribute-table}" in page
    copied = [k for k in registered_attributes() if f"| `{k}` |" in page]
    assert not copied, f"attribute rows pasted into the page: {copied}"


def test_cli_page_is_generated_from_the_parser_the_cli_uses():
    assert "```{mjtouch-cli}" in (DOCS / "reference" / "cli.md").read_text()
    parser = docs_ext().cli_parser()
    commands = set(docs_ext().subcommands(parser))
    usage = subprocess.run(
        [sys.executable, "-m", "mjtouch", "--help"], capture_output=True, text=True, check=True
    ).stdout
    listed = set(re.search(r"\{([a-z,]+)\}", usage).group(1).split(","))
    assert commands == listed and "slide" in commands, (commands, listed)


def test_readme_is_a_front_page_with_the_two_commands_first():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    first_block = text.split("```bash\n", 1)[1].split("```", 1)[0].splitlines()
    assert first_block == [
        "pip install . && python -m mjtouch slide",
        'pip install ".[test]" && python -m pytest',
    ]
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if not target.startswith("http"):
            assert (ROOT / target).exists(), target
    assert (ROOT / "CHANGELOG.md").is_file()
    assert "Apache License" in (ROOT / "LICENSE").read_text()


def test_markdown_docstrings_become_rest():
    lines = [
        "Intro:",
        "- first item",
        "  continued",
        "After the list.",
        "",
        "| key | value |",
        "|---|---|",
        "| ``a`` | F* |",
        "",
        "```python",
        "x = 1",
        "```",
        "The norm |v| of v.",
    ]
    docs_ext().markdown_docstring(None, "module", "m", None, {}, lines)
    text = "\n".join(lines)
    assert "Intro:\n\n- first item\n  continued\n\nAfter the list." in text
    assert ".. list-table::" in text and "     - F\\*" in text
    assert ".. code-block:: python\n\n   x = 1" in text
    assert "The norm \\|v\\| of v." in text
