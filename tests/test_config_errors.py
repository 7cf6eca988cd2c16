"""Bad MJCF attributes fail at compile time with a message naming them."""

import mujoco
import pytest

from conftest import pad_scene

CASES = [
    ({"nx": "-3"}, "`nx`", "[4, 512]"),
    ({"nx": "abc"}, "`nx`", "not an integer"),
    ({"pitch": "0"}, "`pitch`", "(0, 0.01]"),
    ({"poisson": "0.7"}, "`poisson`", "(-1, 0.5]"),
    ({"ridge_pitch": "-1e-3"}, "`ridge_pitch`", "(0, 0.01]"),
    ({"ridge_height": "0"}, "`ridge_height`", "(0, 0.001]"),
    ({"ridges": "maybe"}, "`ridges`", "true or false"),
    ({"stiffness": "-5"}, "`stiffness`", "(0, 1e+12]"),
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
    ({"nx": "1024"}, "`nx`", "[4, 512]"),
    ({"pressure": "fem"}, "`pressure`", "valid: contacts winkler elastic"),
    ({"young": "0"}, "`young`", "(0, 1e+10]"),
    ({"tolerance": "0"}, "`tolerance`", "(0, 0.1]"),
    ({"ridge_profile": "zigzag"}, "`ridge_profile`", "valid: sine triangle square"),
]


@pytest.mark.parametrize("attrs,name,valid", CASES, ids=[next(iter(c[0])) + "=" + next(iter(c[0].values())) for c in CASES])
def test_bad_attribute_fails_at_compile(attrs, name, valid):
    xml = pad_scene(attrs, extra='<geom name="plate_sphere" type="sphere" size="0.001" pos="0.03 0 0.01" contype="0" conaffinity="0"/>')
    with pytest.raises(ValueError) as e:
        mujoco.MjModel.from_xml_string(xml)
    msg = str(e.value)
    assert name in msg and valid in msg, msg


def test_unknown_attribute_fails_at_compile():
    with pytest.raises(ValueError, match="unrecognized attribute|unknown|invalid"):
        mujoco.MjModel.from_xml_string(pad_scene({"bogus": "1"}))


def test_pad_must_be_sphere_ellipsoid_capsule_or_box():
    with pytest.raises(ValueError, match="must be a sphere, ellipsoid, capsule or box"):
        mujoco.MjModel.from_xml_string(pad_scene(pad='type="cylinder" size="0.008 0.007"'))


def test_sdf_texture_cannot_be_rendered():
    # an sdf geom (MuJoCo's torus plugin) in the texture group: no geometry
    # the skin can query
    torus = ('<plugin plugin="mujoco.sdf.torus"><instance name="torus">'
             '<config key="radius1" value="0.01"/><config key="radius2" value="0.003"/>'
             '</instance></plugin>')
    xml = pad_scene({"texture_group": "2"}, extra=(
        '<geom name="knob" type="sdf" mesh="torus" group="2" contype="0" conaffinity="0" '
        'pos="0.03 0 0.01"><plugin instance="torus"/></geom>'))
    xml = xml.replace('<extension><plugin plugin="mjtouch.skin"/></extension>',
                      f'<extension><plugin plugin="mjtouch.skin"/>{torus}</extension>'
                      '<asset><mesh name="torus"><plugin instance="torus"/></mesh></asset>')
    with pytest.raises(ValueError, match="geom 'knob' in `texture_group` 2 cannot be rendered"):
        mujoco.MjModel.from_xml_string(xml)


def test_sensor_must_name_a_geom():
    xml = pad_scene().replace('objtype="geom" objname="pad"', 'objtype="body" objname="finger"')
    with pytest.raises(ValueError, match='objtype="geom"'):
        mujoco.MjModel.from_xml_string(xml)
