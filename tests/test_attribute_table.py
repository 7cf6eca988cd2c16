"""plugin/README.md's attribute table is the one the plugin parses with
(generated from plugin/core/pipeline/attributes.cc; regenerate with
`python .ci/attribute_table.py --write`)."""

import importlib.util
import pathlib

from conftest import registered_attributes

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _tool():
    spec = importlib.util.spec_from_file_location("attribute_table",
                                                  ROOT / ".ci" / "attribute_table.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    return tool


def test_readme_attribute_table_is_generated():
    diff = _tool().diff()
    assert diff == "", ("plugin/README.md's attribute table differs from the plugin's; run "
                        "`python .ci/attribute_table.py --write`:\n" + diff)


def test_readme_table_has_one_row_per_registered_attribute():
    text = _tool().generated()
    keys = [line.split("`")[1] for line in text.splitlines()[2:]]
    assert keys == registered_attributes()


def test_a_changed_readme_row_is_reported(tmp_path, monkeypatch):
    # the check compares the whole section: edit one row of a copy
    tool = _tool()
    edited = tool.README.read_text().replace("| `nx` | 128 |", "| `nx` | 64 |")
    assert edited != tool.README.read_text()
    copy = tmp_path / "README.md"
    copy.write_text(edited)
    monkeypatch.setattr(tool, "README", copy)
    diff = tool.diff()
    assert "-| `nx` | 64 |" in diff and "+| `nx` | 128 |" in diff, diff
