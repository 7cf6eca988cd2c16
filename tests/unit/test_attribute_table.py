"""plugin/README.md's attribute table is the one the plugin parses with
(generated from plugin/core/pipeline/attributes.cc; regenerate with
`python .ci/attribute_table.py --write`)."""

import importlib.util
import pathlib

from conftest import registered_attributes

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _tool():
    spec = importlib.util.spec_from_file_location(
        "attribute_table", ROOT / ".ci" / "attribute_table.py"
    )
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    return tool


def test_readme_attribute_table_is_generated():
    diff = _tool().diff()
    assert diff == "", (
        "plugin/README.md's attribute table differs from the plugin's; run "
        "`python .ci/attribute_table.py --write`:\n" + diff
    )


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


# A valid value different from the default for every physics attribute, with
# the attributes it needs (nx, pitch: a grid that holds the sites).
NON_DEFAULT = {
    "texture_group": "2",
    "nx": "64",
    "pitch": "1.2e-4",
    "ridges": "false",
    "ridge_pitch": "5e-4",
    "ridge_height": "6e-5",
    "ridge_angle": "30",
    "ridge_profile": "square",
    "pressure": "winkler",
    "oversample": "3",
    "substep": "receptors",
    "young": ("5e4", {"skin": "halfspace"}),
    "tolerance": "1e-3",
    "contact_solver": "pk",
    "elastic_precision": "double",
    "grid_shift": "true",
    "grid_cycle": "2",
    "stiffness": "3e7",
    "poisson": ("0.4", {"skin": "halfspace"}),
    "shear": "false",
    "radius": "2e-3",
    "classes": "SA1 RA",
    "density": "70 140 20",
    "depth": "7.5e-4 7.5e-4 1.5e-3",
    "quantity": "szz szz szz",
    "outputs": "spikes",
    "sa1_merkel": "8 5 3",
    "sa1_k0": "2e-16",
    "sa1_k1": "2e-16",
    "sa1_i0": "5e-12",
    "sa1_c": "2e-11",
    "sa1_r": "2e9",
    "sa1_vth": "0.04",
    "ra_gain": "2e-4",
    "ra_lowpass": "50",
    "ra_tau": "6e-3",
    "pc_gain": "6e-6",
    "pc_highpass": "160",
    "pc_lowpass": "260",
    "pc_tau": "2e-3",
    "refractory": "2e-3",
    "noise": "0.1 0 0",
    "noise_tau": "3e-3",
    "seed": "7",
    "rate_tau": "0.1",
    "sites": "SA1 0 0 7.5e-4",
    "stress_method": "direct",
    "stress_theta": ("0.4", {"stress_method": "tree"}),
    "skin": "halfspace",
    "layers": "7e-4 8e4 0.48; 3e-3 3e4 0.45",
    "base": "3e4 0.45",
    "interface_side": "lower",
    "sa1_model": "wang2016",
    "sa1_lowpass": "40",
    "adapt": "0.2 1 1",
    "adapt_tau": "0.05 0.03 0.03",
    "ra_saturation": "4",
    "ra_sustained": "2",
    "ra_sustained_tau": "0.1",
    "pc_refractory": "2e-3",
    "pc_saturation": "4",
    "sa1_saturation": "3e4",
    "population": "uniform",
    "facing": "0 1 0",
    # not physics (the same bits for any count), but read from the shared
    # SkinModel's config, so models with different counts must not share one
    "threads": "2",
}
NOT_PHYSICS = {"texture", "pad_geom", "visual"}  # adapter and drawing only


def _cache_key(attrs: dict) -> str:
    from mjtouch import _core

    return _core.config_cache_key({k: str(v) for k, v in attrs.items()})


def test_every_physics_attribute_changes_the_model_cache_key():
    # models that differ in any physics attribute must not share a SkinModel
    assert set(NON_DEFAULT) | NOT_PHYSICS == set(registered_attributes())
    for key, value in NON_DEFAULT.items():
        value, needs = value if isinstance(value, tuple) else (value, {})
        assert _cache_key(needs) != _cache_key({**needs, key: value}), key


def test_drawing_attributes_do_not_change_the_model_cache_key():
    assert _cache_key({}) == _cache_key({"visual": "none", "texture": "plate"})


# Defaults the table describes in words rather than as a value to write.
DESCRIBED_DEFAULTS = {"texture", "texture_group", "sites", "radius", "layers"}


def test_every_written_default_is_the_parsed_default():
    # The table's default column is text beside the config's initialisers:
    # writing a documented default explicitly must give the same model as
    # leaving the attribute out (it did not when `pressure` changed once).
    from mjtouch import _core

    rows = [
        [f.strip() for f in line.split("|")]
        for line in _core.attribute_table_markdown().splitlines()[2:]
    ]
    defaults = {f[1].strip("`"): f[2] for f in rows}
    assert DESCRIBED_DEFAULTS <= set(defaults)
    for key, text in defaults.items():
        if key in DESCRIBED_DEFAULTS:
            continue
        # attributes that apply only beside another (young: skin="halfspace")
        context = NON_DEFAULT[key][1] if isinstance(NON_DEFAULT.get(key), tuple) else {}
        written, left_out = _cache_key({**context, key: text}), _cache_key(context)
        assert _same_numbers(written, left_out), (key, text, written, left_out)


def _same_numbers(a: str, b: str, rel: float = 1e-9) -> bool:
    """Cache keys equal token by token, numbers to rounding (a default the
    config computes, e.g. sa1_k1 = k0 x ratio, is written to 2-3 digits that
    are exact but for the last bit)."""
    ta, tb = a.split(), b.split()
    if len(ta) != len(tb):
        return False
    for x, y in zip(ta, tb):
        if x == y:
            continue
        try:
            fx, fy = float(x), float(y)
        except ValueError:
            return False
        if not abs(fx - fy) <= rel * max(abs(fx), abs(fy)):
            return False
    return True
