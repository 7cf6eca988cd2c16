"""Bad MJCF attributes fail at compile time with a message naming them."""

import mujoco
import pytest
from conftest import add_geom, pad_scene, pad_spec, registered_attributes

CASES = [
    ({"nx": "-3"}, "`nx`", "[4, 512]"),
    ({"nx": "abc"}, "`nx`", "not an integer"),
    ({"pitch": "0"}, "`pitch`", "[1e-06, 0.01] m"),
    ({"poisson": "0.7"}, "`poisson`", "(-1, 0.5]"),
    ({"ridge_pitch": "-1e-3"}, "`ridge_pitch`", "(0, 0.01]"),
    ({"ridge_height": "0"}, "`ridge_height`", "(0, 0.001]"),
    ({"ridges": "maybe"}, "`ridges`", "true or false"),
    ({"stiffness": "-5"}, "`stiffness`", "[100000, 1e+12] Pa/m"),
    ({"classes": "SA1 XY"}, "`classes`", "valid: SA1 RA PC"),
    ({"density": "70 140"}, "`density`", "3 numbers"),
    ({"density": "70 -1 21"}, "`density` entry 2", "[0, 10000]"),
    ({"depth": "0.75e-3 0.75e-3 0"}, "`depth` entry 3", "(0, 0.02]"),
    ({"quantity": "maxcomp szz foo"}, "`quantity`", "valid: szz maxcomp vonmises maxshear"),
    ({"outputs": "spikes blah"}, "`outputs`", "valid: spikes stress voltage force pressure"),
    ({"radius": "0.02"}, "`radius`", "valid range"),
    ({"ridge_pitch": "2e-4"}, "`ridge_pitch`", "below two taxels"),
    ({"sa1_c": "-1e-12"}, "`sa1_c`", "(0, 1]"),
    ({"refractory": "0"}, "`refractory`", "(0, 1]"),
    ({"texture": "nonexistent"}, "`texture`", "does not exist"),
    ({"texture": "pad"}, "`texture` geom 'pad'", "moves with the pad"),
    ({"texture_group": "9"}, "`texture_group`", "[0, 5]"),
    ({"facing": "0 0 0"}, "`facing`", "3 finite numbers, not all zero"),
    ({"pad_geom": "thumb"}, "`pad_geom` = 'thumb'", "the pad's name as written"),
    ({"nx": "1024"}, "`nx`", "[4, 512]"),
    ({"pressure": "fem"}, "`pressure`", "valid: contacts winkler elastic"),
    ({"young": "0"}, "`young`", "[100, 1e+10] Pa"),
    ({"tolerance": "0"}, "`tolerance`", "(0, 0.1]"),
    ({"contact_solver": "cg"}, "`contact_solver`", "valid: pcg pk"),
    ({"elastic_precision": "half"}, "`elastic_precision`", "valid: float double"),
    ({"ridge_profile": "zigzag"}, "`ridge_profile`", "valid: sine triangle square"),
    ({"pressure": "2"}, "`pressure`", "valid: contacts winkler elastic"),
    ({"young": "soft"}, "`young`", "[100, 1e+10] Pa"),
    ({"young": "2e10"}, "`young`", "[100, 1e+10] Pa"),
    ({"tolerance": "-1e-3"}, "`tolerance`", "(0, 0.1]"),
    ({"tolerance": "0.2"}, "`tolerance`", "(0, 0.1]"),
    ({"pitch": "nan"}, "`pitch`", "[1e-06, 0.01] m"),
    ({"pitch": "inf"}, "`pitch`", "[1e-06, 0.01] m"),
    ({"pitch": "1e-4 2e-4"}, "`pitch`", "[1e-06, 0.01] m"),
    ({"ridge_angle": "181"}, "`ridge_angle`", "[-180, 180] deg"),
    ({"shear": "yes"}, "`shear`", "valid: true (full slip) false partial"),
    ({"grid_shift": "half"}, "`grid_shift`", "true or false"),
    ({"grid_cycle": "5"}, "`grid_cycle`", "[1, 4]"),
    ({"grid_cycle": "2.5"}, "`grid_cycle`", "not an integer"),
    ({"texture_group": "2.5"}, "`texture_group`", "not an integer; valid range [0, 5]"),
    ({"stiffness": "stiff"}, "`stiffness`", "[100000, 1e+12] Pa/m"),
    ({"sa1_k0": "-1e-16"}, "`sa1_k0`", "[0, 1e-06]"),
    ({"sa1_k1": "2e-6"}, "`sa1_k1`", "[0, 1e-06]"),
    ({"sa1_i0": "2e-6"}, "`sa1_i0`", "[-1e-06, 1e-06] A"),
    ({"sa1_r": "0"}, "`sa1_r`", "(0, 1e+15] Ohm"),
    ({"sa1_vth": "11"}, "`sa1_vth`", "(0, 10] V"),
    ({"ra_gain": "-1"}, "`ra_gain`", "[0, 1] s/Pa"),
    ({"ra_tau": "0"}, "`ra_tau`", "(0, 10] s"),
    ({"pc_gain": "2"}, "`pc_gain`", "[0, 1] s^2/Pa"),
    ({"pc_tau": "11"}, "`pc_tau`", "(0, 10] s"),
    ({"pc_highpass": "0"}, "`pc_highpass`", "(0, 100000] Hz"),
    ({"sa1_model": "lesniak"}, "`sa1_model`", "valid: filtered wang2016"),
    ({"sa1_lowpass": "0"}, "`sa1_lowpass`", "(0, 10000] Hz"),
    ({"adapt": "1 -1 0"}, "`adapt` entry 2", "[0, 100]"),
    ({"adapt_tau": "0.05 0 0.02"}, "`adapt_tau` entry 2", "(0, 10]"),
    ({"ra_saturation": "-1"}, "`ra_saturation`", "[0, 1e+06]"),
    ({"ra_sustained": "-1"}, "`ra_sustained`", "[0, 1e+06]"),
    ({"ra_sustained_tau": "0"}, "`ra_sustained_tau`", "(0, 10]"),
    ({"pc_saturation": "-1"}, "`pc_saturation`", "[0, 1e+06]"),
    ({"pc_refractory": "0"}, "`pc_refractory`", "(0, 1]"),
    ({"sa1_saturation": "-1"}, "`sa1_saturation`", "[0, 1e+12] units of q"),
    ({"population": "random"}, "`population`", "valid: uniform varied"),
    # explicit receptor sites
    ({"sites": "SA1 0 0"}, "`sites` entry 1 has 3 words", "'CLASS x y depth' (CLASS in SA1 RA PC"),
    ({"sites": "XX 0 0 1e-3"}, "`sites` entry 1", "CLASS in SA1 RA PC"),
    ({"sites": "SA1 abc 0 1e-3"}, "`sites` entry 1", "x, y, depth in m"),
    (
        {"sites": "SA1 0 0 1e-3; RA 0.01 0 1e-3"},
        "`sites` entry 2",
        "|x|, |y| <= nx * pitch / 2 - pitch = 0.00345 m",
    ),
    ({"sites": "PC 0 0 0"}, "`sites` entry 1", "(0, 0.02] m"),
    ({"sites": "PC 0 0 0.03"}, "`sites` entry 1", "(0, 0.02] m"),
    ({"sites": "SA1 0 0 1e-3; SA1 1e-3 0 2e-3"}, "`sites` entry 2", "the same depth"),
    ({"sites": "SA1 0 0 1e-3", "density": "70 140 21"}, "remove `density`", "valid with `sites`"),
    ({"sites": "SA1 0 0 1e-3", "radius": "2e-3"}, "remove `radius`", "valid with `sites`"),
    # afferent parameters
    ({"noise": "1 2"}, "`noise`", "3 numbers (SA1 RA PC), each in [0, 100]"),
    ({"noise": "-1 0 0"}, "`noise` entry 1", "[0, 100]"),
    ({"noise": "0 0 101"}, "`noise` entry 3", "[0, 100]"),
    ({"noise": "0 low 0"}, "`noise` entry 2", "[0, 100]"),
    ({"noise_tau": "0"}, "`noise_tau`", "(0, 10] s"),
    ({"noise_tau": "slow"}, "`noise_tau`", "(0, 10] s"),
    ({"seed": "-1"}, "`seed`", "[0, 18446744073709551615]"),
    ({"seed": "1.5"}, "`seed`", "[0, 18446744073709551615]"),
    ({"seed": "18446744073709551616"}, "`seed`", "[0, 18446744073709551615]"),
    ({"rate_tau": "0"}, "`rate_tau`", "(0, 100] s"),
    ({"rate_tau": "101"}, "`rate_tau`", "(0, 100] s"),
    ({"outputs": "rate", "rate_tau": "fast"}, "`rate_tau`", "(0, 100] s"),
    ({"outputs": "spikes rates"}, "`outputs`", "valid: spikes stress voltage force pressure rate"),
    ({"visual": "all"}, "`visual`", "none pad above both"),
    ({"sa1_merkel": "8 5 3 1 2"}, "`sa1_merkel`", "1 to 4 numbers in [0, 1000]"),
    ({"sa1_merkel": "8 -1"}, "`sa1_merkel`", "1 to 4 numbers in [0, 1000]"),
    ({"sa1_merkel": "1001"}, "`sa1_merkel`", "1 to 4 numbers in [0, 1000]"),
    ({"sa1_merkel": "many"}, "`sa1_merkel`", "1 to 4 numbers in [0, 1000]"),
    ({"ra_lowpass": "0"}, "`ra_lowpass`", "(0, 10000] Hz"),
    ({"ra_lowpass": "2e4"}, "`ra_lowpass`", "(0, 10000] Hz"),
    ({"pc_lowpass": "-5"}, "`pc_lowpass`", "(0, 100000] Hz"),
    ({"pc_lowpass": "2e5"}, "`pc_lowpass`", "(0, 100000] Hz"),
    # the elastic skin (more in tests/unit/test_layered.py)
    ({"stress_method": "gpu"}, "`stress_method`", "tree direct fft auto"),
    ({"stress_method": "tree", "stress_theta": "0"}, "`stress_theta`", "(0, 2]"),
    ({"stress_method": "tree", "stress_theta": "2.5"}, "`stress_theta`", "(0, 2]"),
    ({"stress_theta": "0.3"}, "`stress_theta`", 'stress_method="tree" only'),
    ({"threads": "0"}, "`threads`", "[1, 64]"),
    ({"threads": "65"}, "`threads`", "[1, 64]"),
    ({"threads": "1.5"}, "`threads`", "not an integer"),
    ({"oversample": "0"}, "`oversample`", "auto or an integer in [1, 64]"),
    ({"oversample": "2.5"}, "`oversample`", "auto or an integer in [1, 64]"),
    ({"oversample": "65"}, "`oversample`", "auto or an integer in [1, 64]"),
    ({"oversample": "2", "pressure": "contacts"}, "`oversample`", "valid with contacts: 1"),
    ({"substep": "ramp"}, "`substep`", "valid: full receptors"),
    ({"skin": "foam"}, "`skin`", "layered halfspace"),
    ({"layers": "1e-3 5e4 0.45 2"}, "`layers`", "needs 3 numbers"),
    ({"layers": "2 5e4 0.45"}, "`layers`", "[1e-06, 1] m"),
    ({"base": "5e4"}, "`base`", "nu in (-1, 0.5]"),
    ({"base": "5e4 0.45", "skin": "halfspace"}, "`base`", 'skin="layered" only'),
    ({"interface_side": "both"}, "`interface_side`", "upper lower"),
    # lower bounds that keep the output finite and physical (values near
    # 1e-300 gave inf/NaN sensordata or an all-zero force block)
    ({"pitch": "1e-308"}, "`pitch` = 1e-308", "[1e-06, 0.01] m"),
    ({"pitch": "9e-7"}, "`pitch` = 9e-07", "[1e-06, 0.01] m"),
    (
        {"young": "1e-20", "skin": "halfspace", "pressure": "elastic"},
        "`young` = 1e-20",
        "[100, 1e+10] Pa",
    ),
    ({"young": "99", "skin": "halfspace"}, "`young` = 99", "[100, 1e+10] Pa"),
    ({"stiffness": "1e-308"}, "`stiffness` = 1e-308", "[100000, 1e+12] Pa/m"),
    ({"stiffness": "9e4"}, "`stiffness` = 90000", "[100000, 1e+12] Pa/m"),
    ({"layers": "7e-4 1e-20 0.48"}, "`layers`: layer 1 E = '1e-20'", "[100, 2e+10] Pa"),
    ({"layers": "7e-4 8e4 0.48; 8e-4 99 0.48"}, "`layers`: layer 2 E = '99'", "[100, 2e+10] Pa"),
    ({"base": "1e-308 0.45"}, "`base`: E = '1e-308'", "[100, 2e+10] Pa"),
    # present but blank (MuJoCo keeps whitespace; value="" is stored as unset)
    ({"nx": " "}, "`nx` is empty", "[4, 512]"),
    ({"pitch": "  "}, "`pitch` is empty", "[1e-06, 0.01] m"),
    ({"young": " ", "skin": "halfspace"}, "`young` is empty", "[100, 1e+10] Pa"),
    ({"density": " "}, "`density` is empty", "3 numbers (SA1 RA PC), each in [0, 10000] per cm^2"),
    ({"pressure": " "}, "`pressure` is empty", "contacts winkler elastic"),
    ({"layers": "\t"}, "`layers` is empty", "1 to 64 layers"),
    ({"sites": " "}, "`sites` is empty", "CLASS x y depth"),
    # one grammar for composite values: entries separated by ';', words by
    # spaces; ',' is no separator and no entry is empty
    ({"sites": ";"}, "`sites`: entry 1 is empty", "separated by ';'"),
    ({"sites": "SA1 0 0 1e-3;"}, "`sites`: entry 2 is empty", "separated by ';'"),
    ({"sites": "SA1,0,0,1e-3"}, "`sites`: ',' is not a separator", "entries by ';'"),
    ({"layers": "7e-4 8e4 0.48;; 8e-4 5e4 0.48"}, "`layers`: entry 2 is empty", "separated by ';'"),
    (
        {"layers": "7e-4 8e4 0.48, 8e-4 5e4 0.48"},
        "`layers`: ',' is not a separator",
        "'thickness E nu'",
    ),
    (
        {"density": "70,140,21"},
        "`density` = '70,140,21': ',' is not a separator",
        "separated by spaces",
    ),
    (
        {"noise": "0.3; 0.3; 0.1"},
        "`noise` = '0.3; 0.3; 0.1': ';' is not a separator",
        "separated by spaces",
    ),
    ({"classes": "SA1,RA"}, "`classes` = 'SA1,RA': ',' is not a separator", "SA1 RA PC"),
    ({"outputs": "spikes;force"}, "`outputs` = 'spikes;force': ';'", "spikes stress voltage"),
    ({"base": "5e4,0.45"}, "`base` = '5e4,0.45': ','", "'rigid' or 'E nu'"),
    # physical ranges: a layer stiffer than bone, thinner than any tissue
    ({"layers": "1e-3 1e12 0.48"}, "`layers`: layer 1 E = '1e12' Pa is above", "[100, 2e+10] Pa"),
    ({"base": "1e12 0.3"}, "`base`: E = '1e12' Pa is above", "[100, 2e+10] Pa"),
    (
        {"layers": "1e-30 8e4 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 0.4"},
        "`layers`: layer 1 thickness = '1e-30' m is below",
        "[1e-06, 1] m",
    ),
    (
        {"layers": "1e-300 8e4 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 0.4"},
        "`layers`: layer 1 thickness = '1e-300' m is below",
        "[1e-06, 1] m",
    ),
    (
        {"layers": "7e-4 8e4 0.48; 1e-7 5e4 0.48"},
        "`layers`: layer 2 thickness = '1e-7' m",
        "[1e-06, 1] m",
    ),
    # in range, but more work than a compile may take: the bound says what to change
    (
        {
            "nx": "128",
            "pitch": "1e-4",
            "layers": "1.5e-6 8e4 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 0.4",
        },
        "`layers`: layer 1 thickness = 1.5e-06 m is below",
        "or a smaller `nx` x `pitch`",
    ),
    # a class that gets no receptor: an error naming why, not empty blocks
    ({"nx": "4", "pitch": "1e-6"}, "no SA1 receptor", "(default): min(5e-3, `nx` * `pitch` / 2"),
    ({"radius": "0"}, "no SA1 receptor", "raise `density` or `radius`"),
    ({"radius": "1e-30"}, "no SA1 receptor", "raise `density` or `radius`"),
    ({"density": "0 0 0"}, "no SA1 receptor", "remove SA1 from `classes`"),
    ({"density": "70 140 0"}, "no PC receptor", "remove PC from `classes`"),
]


@pytest.mark.parametrize(
    "attrs,name,valid", CASES, ids=[";".join(f"{k}={v}" for k, v in c[0].items()) for c in CASES]
)
def test_bad_attribute_fails_at_compile(attrs, name, valid):
    spec = pad_spec(attrs)
    add_geom(
        spec.worldbody,
        "sphere",
        [0.001],
        name="plate_sphere",
        pos=[0.03, 0, 0.01],
        contype=0,
        conaffinity=0,
    )
    with pytest.raises(ValueError) as e:
        spec.compile()
    msg = str(e.value)
    # the plugin's own message (a line of MuJoCo's error) names the
    # attribute and its valid range
    ours = [line for line in msg.splitlines() if line.startswith("mjtouch.skin: ")]
    assert ours, msg
    assert name in ours[0] and valid in ours[0], msg
    # one message, once: not repeated, not behind MuJoCo's init failure
    assert len(ours) == 1 and msg.count(ours[0]) == 1, msg
    assert "plugin->init failed" not in msg, msg


@pytest.mark.parametrize(
    "key,value,timestep", [("pc_lowpass", "1e5", 1e-4), ("ra_lowpass", "1e4", 1e-3)]
)
def test_sampling_advice_can_be_followed(key, value, timestep):
    # e.g. dt 1e-4: even oversample 64 samples 640 kHz, below 8 x 100 kHz;
    # the message must not ask for an oversample past its range but name a
    # corner (or timestep) that compiles
    import re

    attrs = {key: value, "oversample": "auto", "classes": "SA1 RA PC"}
    spec = pad_spec(attrs)
    spec.option.timestep = timestep
    with pytest.raises(ValueError) as e:
        spec.compile()
    msg = str(e.value)
    assert "`oversample` >=" not in msg, msg
    corner = re.search(rf"set `{key}` <= ([0-9.e+]+) Hz, or the timestep <= ([0-9.e+-]+) s", msg)
    assert corner, msg
    for fix, dt in ((corner.group(1), timestep), (value, float(corner.group(2)))):
        spec = pad_spec({**attrs, key: fix})
        spec.option.timestep = dt
        spec.compile()


def test_sampling_advice_within_range_names_oversample():
    spec = pad_spec({"pc_lowpass": "3000", "oversample": "2"})
    spec.option.timestep = 1e-4
    with pytest.raises(ValueError, match=r"set `oversample` >= 3 \(valid \[1, 64\]\)"):
        spec.compile()


def test_every_attribute_is_checked_here_or_in_test_layered():
    # every key the plugin registers has a bad-input case in CASES (or in
    # tests/unit/test_layered.py's BAD for the elastic skin)
    from test_layered import BAD

    covered = {k for attrs, *_ in CASES + BAD for k in attrs}
    assert set(registered_attributes()) - covered == set()


@pytest.mark.parametrize("outputs", ["rate", "spikes rate", "rate pressure force"])
def test_rate_output_is_accepted(outputs):
    # the counterpart of the `outputs` error: `rate` is a valid block
    from mjtouch.scene.sensor import SkinLayout

    m = mujoco.MjModel.from_xml_string(pad_scene({"outputs": outputs, "rate_tau": "0.05"}))
    layout = SkinLayout.from_model(m)
    assert set(layout.blocks) == set(outputs.split())
    assert layout.blocks["rate"].stop - layout.blocks["rate"].start == len(layout.classes)


def test_unknown_attribute_fails_at_compile():
    with pytest.raises(ValueError, match="unrecognized attribute|unknown|invalid"):
        mujoco.MjModel.from_xml_string(pad_scene({"bogus": "1"}))


def test_pad_must_be_sphere_ellipsoid_capsule_box_or_mesh():
    with pytest.raises(ValueError, match="must be a sphere, ellipsoid, capsule, box or mesh"):
        pad_spec(pad={"kind": "cylinder", "size": [0.008, 0.007]}).compile()


def test_sdf_texture_cannot_be_rendered():
    # an sdf geom (MuJoCo's torus plugin) in the texture group: no geometry
    # the skin can query
    spec = mujoco.MjSpec.from_string(pad_scene({"texture_group": "2"}))
    spec.activate_plugin("mujoco.sdf.torus")
    torus = spec.add_plugin(name="torus", plugin_name="mujoco.sdf.torus", active=True)
    torus.config = {"radius1": "0.01", "radius2": "0.003"}
    spec.add_mesh(name="torus").plugin = torus
    knob = spec.worldbody.add_geom(
        name="knob",
        type=mujoco.mjtGeom.mjGEOM_SDF,
        meshname="torus",
        group=2,
        contype=0,
        conaffinity=0,
        pos=[0.03, 0, 0.01],
    )
    knob.plugin = torus
    with pytest.raises(ValueError, match="geom 'knob' in `texture_group` 2 cannot be rendered"):
        spec.compile()


def test_sensor_must_name_a_geom():
    spec = mujoco.MjSpec.from_string(pad_scene())
    spec.sensors[0].objtype = mujoco.mjtObj.mjOBJ_BODY
    spec.sensors[0].objname = "finger"
    with pytest.raises(ValueError, match='objtype="geom"'):
        spec.compile()


# -- messages that name the wrong thing, or twice (plugin bugs, see below) ---


def _plugin_lines(attrs):
    with pytest.raises(ValueError) as e:
        mujoco.MjModel.from_xml_string(pad_scene(attrs))
    return [line for line in str(e.value).splitlines() if line.startswith("mjtouch.skin: ")]


def test_too_deep_site_names_sites():
    # The depth comes from `sites`, which the user set; `depth` was not set.
    line = _plugin_lines({"sites": "SA1 0 0 0.01"})[0]
    assert "`sites`" in line and "(0, 0.004]" in line, line


def test_default_ridge_pitch_against_pitch_says_default():
    # The user set `pitch`; `ridge_pitch` is at its default: the message
    # must say so (as the `radius` message does) or name `pitch`.
    line = _plugin_lines({"nx": "24", "pitch": "1.7e-3"})[0]
    assert "(default)" in line or "`pitch`" in line, line


# -- a plugin built for another MuJoCo -----------------------------------------


def test_loader_refuses_a_plugin_built_for_another_mujoco(monkeypatch):
    # The Python loader compares the MuJoCo the library was compiled against
    # (mjtouch_built_mujoco_version) with the installed mujoco: pretend an
    # older mujoco is installed and load the library afresh.
    import importlib.metadata

    from mjtouch import _loader

    real_version = importlib.metadata.version
    monkeypatch.setattr(
        importlib.metadata,
        "version",
        lambda name: "3.3.7" if name == "mujoco" else real_version(name),
    )
    monkeypatch.setattr(_loader, "_handle", None)
    with pytest.raises(_loader.PluginNotBuiltError) as e:
        _loader.load()
    msg = str(e.value)
    assert f"compiled against MuJoCo {mujoco.__version__} but mujoco 3.3.7 is installed" in msg, msg
    assert "pip install ." in msg


SHIM_C = r"""
/* Pretends the running MuJoCo is 3.3.7: interposes mj_version. */
int mj_version(void) { return 3003007; }
"""

PROBE_PY = r"""
import ctypes, sys
mj = ctypes.CDLL(sys.argv[1], mode=ctypes.RTLD_GLOBAL)
mj.mjp_getPlugin.restype = ctypes.c_void_p
mj.mjp_getPlugin.argtypes = [ctypes.c_char_p, ctypes.c_void_p]
ctypes.CDLL(sys.argv[2])  # its constructor registers mjtouch.skin, or refuses
print("registered:", bool(mj.mjp_getPlugin(b"mjtouch.skin", None)), flush=True)
"""


@pytest.mark.parametrize("mismatch", [False, True], ids=["same", "other_version"])
def test_library_refuses_to_register_under_another_mujoco(tmp_path, mismatch):
    # The C side (plugin/mujoco/register.cc): loaded into a process whose
    # libmujoco reports another version (mj_version interposed through
    # LD_PRELOAD), the library must not register and must say why.
    import os
    import pathlib
    import shutil
    import subprocess
    import sys

    from mjtouch import _loader

    libmujoco = sorted(pathlib.Path(mujoco.__file__).parent.glob("libmujoco.so.*"))[0]
    env = dict(os.environ)
    if mismatch:
        cc = os.environ.get("CC") or shutil.which("gcc") or shutil.which("cc")
        assert cc, "no C compiler on PATH"
        (tmp_path / "shim.c").write_text(SHIM_C)
        build = subprocess.run(
            [cc, "-shared", "-fPIC", "-o", str(tmp_path / "shim.so"), str(tmp_path / "shim.c")],
            capture_output=True,
            text=True,
        )
        assert build.returncode == 0, build.stderr
        # after any sanitizer runtime already preloaded (it must come first)
        env["LD_PRELOAD"] = f"{env.get('LD_PRELOAD', '')} {tmp_path / 'shim.so'}".strip()
    (tmp_path / "probe.py").write_text(PROBE_PY)
    run = subprocess.run(
        [sys.executable, str(tmp_path / "probe.py"), str(libmujoco), str(_loader.library_path())],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=120,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    log = (
        (tmp_path / "MUJOCO_LOG.TXT").read_text() if (tmp_path / "MUJOCO_LOG.TXT").exists() else ""
    )
    said = run.stdout + run.stderr + log
    if mismatch:
        assert "registered: False" in run.stdout
        built = _loader.load().mjtouch_built_mujoco_version()
        assert (
            f"mjtouch: plugin built for MuJoCo {built} but running MuJoCo 3003007; not registered"
        ) in said, said
    else:
        assert "registered: True" in run.stdout
        assert "mjtouch" not in said.replace("registered: True", ""), said
