"""Mitsuba 3 XML scene files and serialized meshes: every XML feature the
reader takes, read from files written here, against Mitsuba's own
``mi.load_file`` (geometry, camera, and a per-pixel z-test of the renders),
and the errors that name the file and line."""

import struct
import zlib

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats
from mcsample.scene import read_serialized, read_xml
from scenes import skip_scalar


def serialized_mesh(vertices, faces, normals=None, version=4, double=False,
                    face_normals=False):
    """One mesh of Mitsuba's serialized format (written from its layout)."""
    flags = (0x2000 if double else 0x1000) | (0x1 if normals is not None else 0) \
        | (0x10 if face_normals else 0)
    real = "<f8" if double else "<f4"
    body = struct.pack("<I", flags) + (b"mesh\0" if version >= 4 else b"")
    body += struct.pack("<QQ", len(vertices), len(faces)) + np.asarray(vertices, real).tobytes()
    if normals is not None:
        body += np.asarray(normals, real).tobytes()
    body += np.asarray(faces, "<u4").tobytes()
    return struct.pack("<HH", 0x041C, version) + zlib.compress(body)


def write_serialized(path, meshes, version=4, double=False):
    """A serialized file of several meshes with its table of offsets."""
    data, offsets = b"", []
    for mesh in meshes:
        offsets.append(len(data))
        data += serialized_mesh(*mesh, version=version, double=double)
    data += b"".join(struct.pack("<Q" if version >= 4 else "<I", o) for o in offsets)
    path.write_bytes(data + struct.pack("<I", len(meshes)))


V0 = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
F0 = [[0, 1, 2]]
V1 = np.array([[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0.2]], dtype=np.float64)
F1 = [[0, 1, 2], [1, 3, 2]]
N1 = np.tile([0.0, 0.0, 1.0], (4, 1))


@pytest.mark.parametrize("version", [3, 4])
@pytest.mark.parametrize("double", [False, True])
def test_serialized_meshes_read_as_written(tmp_path, version, double):
    path = tmp_path / "two.serialized"
    write_serialized(path, [(V0, F0), (V1, F1, N1)], version=version, double=double)
    v, f, n = read_serialized(path)
    assert np.array_equal(v, V0) and f.tolist() == F0 and n is None
    v, f, n = read_serialized(path, 1)
    assert np.allclose(v, V1, atol=1e-7) and f.tolist() == F1 and np.array_equal(n, N1)
    with pytest.raises(ValueError, match="shape_index = 2"):
        read_serialized(path, 2)


@pytest.mark.mitsuba
def test_serialized_meshes_agree_with_mitsuba(mi, tmp_path):
    path = tmp_path / "two.serialized"
    write_serialized(path, [(V0, F0), (V1, F1, N1)])
    for index, expected in [(0, V0), (1, V1)]:
        shape = mi.load_dict({"type": "serialized", "filename": str(path),
                              "shape_index": index})
        theirs = np.array(mi.traverse(shape)["vertex_positions"]).reshape(-1, 3)
        ours = read_serialized(path, index)[0]
        assert np.allclose(ours, theirs, atol=1e-6) and np.allclose(ours, expected, atol=1e-6)


def test_bad_serialized_files(tmp_path):
    bad = tmp_path / "bad.serialized"
    bad.write_bytes(b"\x1c\x04\x04\x00" + b"not zlib")
    with pytest.raises(ValueError, match="bad.serialized: the mesh's zlib stream"):
        read_serialized(bad)
    bad.write_bytes(b"PLY!")
    with pytest.raises(ValueError, match="not a Mitsuba serialized mesh"):
        read_serialized(bad)
    short = serialized_mesh(V1, F1)
    body = zlib.decompress(short[4:])[:-8]  # one index short
    bad.write_bytes(short[:4] + zlib.compress(body))
    with pytest.raises(ValueError, match="ends early"):
        read_serialized(bad)
    with pytest.raises(OSError):
        read_serialized(tmp_path / "missing.serialized")


# A closed box lit by a small area light near the ceiling and a dim
# constant environment through the open front, written with every feature
# of the reader: <default> and $name (also in a transform), <include> (the
# materials after the references to them, a shape from a subfolder), id and
# <ref>, all the transform operations, rgb / spectrum / float / integer /
# boolean / string values, and a serialized mesh.
SCENE = """<?xml version="1.0"?>
<scene version="3.0.0">
    <default name="spp" value="16"/>
    <default name="res" value="48"/>
    <default name="light" value="12"/>
    <default name="cube_x" value="0.3"/>
    <integrator type="path">
        <integer name="max_depth" value="4"/>
        <boolean name="hide_emitters" value="false"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <string name="fov_axis" value="x"/>
        <transform name="to_world">
            <lookat origin="0, 0.2, 3.6" target="0 0 0" up="0 1 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <rfilter type="box"/>
        </film>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
    </sensor>
    <emitter type="constant">
        <spectrum name="radiance" value="0.2"/>
    </emitter>
    <shape type="rectangle" id="floor">
        <transform name="to_world">
            <rotate x="1" angle="-90"/>
            <translate y="-1"/>
        </transform>
        <ref id="white"/>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <rotate value="0 1 0" angle="90"/>
            <translate value="-1 0 0"/>
        </transform>
        <ref name="bsdf" id="red"/>
    </shape>
    <include filename="parts/wall.xml"/>
    <shape type="cube">
        <transform name="to_world">
            <scale value="0.3"/>
            <rotate y="1" angle="30"/>
            <translate x="$cube_x" y="-0.7" z="0.1"/>
        </transform>
        <bsdf type="twosided">
            <bsdf type="diffuse">
                <rgb name="reflectance" value="0.3, 0.6, 0.3"/>
            </bsdf>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="-0.4" y="-0.6" z="-0.2"/>
        <float name="radius" value="0.35"/>
        <ref id="white"/>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale x="0.15" y="0.15"/>
            <rotate x="1" angle="90"/>
            <translate y="0.95"/>
        </transform>
        <emitter type="area">
            <rgb name="radiance" value="$light"/>
        </emitter>
    </shape>
    <include filename="materials.xml"/>
</scene>
"""

# Included from a subfolder; its mesh's file name is relative to the main
# scene's folder, as Mitsuba resolves it.
WALL = """<scene version="3.0.0">
    <shape type="serialized">
        <string name="filename" value="wall.serialized"/>
        <integer name="shape_index" value="1"/>
        <transform name="to_world">
            <matrix value="0 0 -1 1  0 1 0 0  1 0 0 0  0 0 0 1"/>
        </transform>
        <ref id="white"/>
    </shape>
</scene>
"""

MATERIALS = """<scene version="3.0.0">
    <bsdf type="diffuse" id="white">
        <rgb name="reflectance" value="0.7"/>
    </bsdf>
    <bsdf type="diffuse" id="red">
        <rgb name="reflectance" value="0.6 0.1 0.1"/>
    </bsdf>
</scene>
"""


@pytest.fixture
def scene_file(tmp_path):
    (tmp_path / "scene.xml").write_text(SCENE)
    (tmp_path / "materials.xml").write_text(MATERIALS)
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "wall.xml").write_text(WALL)
    # The back wall: a unit square in x = 0 facing +x, mapped by the matrix
    # to z = -1 facing +z.
    wall = np.array([[0, -1, -1], [0, 1, -1], [0, 1, 1], [0, -1, 1]], dtype=np.float64)
    write_serialized(tmp_path / "wall.serialized",
                     [(V0, F0), (wall, [[0, 1, 2], [2, 3, 0]])])
    return tmp_path / "scene.xml"


def test_every_feature_is_read(scene_file):
    d = read_xml(scene_file, res=32)
    assert d["sensor_1"]["film"]["width"] == 32  # the call's value wins
    assert d["sensor_1"]["sampler"]["sample_count"] == 16  # the <default>
    assert d["white"] == {"type": "diffuse", "id": "white",
                          "reflectance": {"type": "rgb", "value": [0.7] * 3}}
    assert d["floor"]["bsdf"] == {"type": "ref", "id": "white"}
    assert d["shape_2"]["bsdf"] == {"type": "ref", "id": "red"}
    assert d["emitter_1"]["radiance"] == {"type": "spectrum", "value": 0.2}
    assert d["shape_5"]["center"] == [-0.4, -0.6, -0.2]
    assert d["shape_3"]["filename"] == str(scene_file.parent / "wall.serialized")
    assert d["shape_3"]["bsdf"] == {"type": "ref", "id": "white"}
    assert np.allclose(d["shape_4"]["to_world"][:3, 3], [0.3, -0.7, 0.1])
    assert d["integrator_1"] == {"type": "path", "max_depth": 4, "hide_emitters": False}
    # rotate, then translate: the floor's normal (+z) turned to +y, at y = -1.
    floor = d["floor"]["to_world"]
    assert np.allclose(floor @ [0, 0, 1, 0], [0, 1, 0, 0], atol=1e-12)
    assert np.allclose(floor @ [0, 0, 0, 1], [0, -1, 0, 1])
    scene = mcs.Scene.from_mitsuba(scene_file)
    assert len(scene.shapes) == 6 and scene.camera.width == 48
    assert sum(s.emission is not None for s in scene.shapes) == 1


@pytest.mark.mitsuba
def test_geometry_and_camera_agree_with_mitsuba(mi, scene_file):
    ours = mcs.Scene.from_mitsuba(scene_file)
    theirs = mi.load_file(str(scene_file))
    cam = np.array(theirs.sensors()[0].world_transform().matrix, dtype=np.float64).reshape(4, 4)
    assert np.allclose(ours.camera.to_world, cam, atol=1e-5)

    def boxes(shapes):
        return sorted(tuple(np.round(b, 4).ravel()) for b in shapes)

    our_boxes = []
    for s in ours.shapes:
        if s.kind == "sphere":
            c = np.array(s.center)
            our_boxes.append(np.array([c - s.radius, c + s.radius]))
        else:
            our_boxes.append(np.array([s.vertices.min(axis=0), s.vertices.max(axis=0)]))
    their_boxes = [np.array([np.ravel(s.bbox().min), np.ravel(s.bbox().max)])
                   for s in theirs.shapes()]
    assert np.allclose(boxes(our_boxes), boxes(their_boxes), atol=2e-4)


@pytest.mark.mitsuba
def test_render_agrees_with_mitsubas_load_file(mi, scene_file):
    """Per-pixel z-test of mcsample's render of the file against Mitsuba's
    render of the same file, whose per-pixel variance comes from 16
    independent renders (an unbiased reference, no moment integrator
    needed)."""
    ours = mcs.render(mcs.Scene.from_mitsuba(scene_file), 256, seed=3)
    ref = mcs.mitsuba.render_runs(mi.load_file(str(scene_file)), 16)
    result = stats.render_ztest(ours, ref)
    assert result.passed, result
    # Power: a light 20 % brighter in one of them (it lights a sixth of the
    # image) is seen.
    brighter = mcs.render(mcs.Scene.from_mitsuba(scene_file, light=14.4), 256, seed=3)
    assert not stats.render_ztest(brighter, ref).passed


def test_errors_name_the_file_and_line(tmp_path, scene_file):
    def write(text, name="bad.xml"):
        path = tmp_path / name
        path.write_text(text)
        return path

    cases = [
        ('<scene version="3.0.0">\n<shape type="sphere">\n</scene>', "bad.xml:3: not well-formed"),
        ('<scene version="3.0.0">\n\n<shape type="sphere"><float name="radius" value="$r"/>'
         '</shape></scene>', r"bad.xml:3: <float>: \$r is not a parameter"),
        ('<scene version="3.0.0">\n<shape type="sphere"><transform name="to_world">'
         '<scale value="0"/></transform></shape></scene>', "bad.xml:2: <transform>: .*singular"),
        ('<scene version="3.0.0">\n<shapes type="sphere"/></scene>',
         "bad.xml:2: <shapes>: not a tag"),
        ('<scene version="3.0.0">\n<include filename="bad.xml"/></scene>', "cyclic <include>"),
        ('<scene version="3.0.0">\n\n\n<shape type="sphere"><bsdf type="conductor"/></shape>'
         '</scene>', r"bad.xml:4: shape_1.bsdf.type = 'conductor'"),
        ('<scene version="3.0.0">\n<shape type="sphere"><float name="radius" value="x"/>'
         '</shape></scene>', "bad.xml:2: <float>: 'x' is not a list of numbers"),
    ]
    for text, match in cases:
        with pytest.raises(ValueError, match=match):
            mcs.Scene.from_mitsuba(write(text))
    with pytest.raises(OSError, match="missing.xml"):
        mcs.Scene.from_mitsuba(tmp_path / "missing.xml")
    with pytest.raises(OSError, match="nothing.xml"):
        mcs.Scene.from_mitsuba(write('<scene version="3.0.0"><include filename="nothing.xml"/>'
                                     '</scene>'))
    mesh = write('<scene version="3.0.0"><shape type="serialized">'
                 '<string name="filename" value="none.serialized"/></shape></scene>')
    with pytest.raises(OSError, match="none.serialized"):
        mcs.Scene.from_mitsuba(mesh)
    with pytest.raises(ValueError, match="parameters are for a scene file"):
        mcs.Scene.from_mitsuba({"type": "scene"}, spp=4)


@pytest.mark.mitsuba
def test_defaults_and_spectra_as_mitsuba_reads_them(mi):
    """A shape without a bsdf is diffuse 0.5, black if it emits; an
    emitter's constant spectrum is the equal-energy colour, a bsdf's is
    grey: each compared with what Mitsuba loads from the same dict."""
    light = {"type": "rectangle", "emitter": {"type": "area", "radiance": 3.0}}
    plain = {"type": "rectangle"}
    sky = {"type": "constant", "radiance": {"type": "spectrum", "value": 0.2}}
    grey = {"type": "rectangle",
            "bsdf": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.3}}}
    sensor = {"type": "perspective", "fov": 40}
    scene = mcs.Scene.from_mitsuba({"type": "scene", "light": light, "plain": plain,
                                    "sky": sky, "grey": grey, "sensor": sensor})
    ours = {k: s.material.diffuse for k, s in zip(("light", "plain", "grey"), scene.shapes)}
    for key, d in (("light", light), ("plain", plain), ("grey", grey)):
        params = mi.traverse(mi.load_dict(d))
        theirs = np.ravel(params["bsdf.reflectance.value"])
        assert np.allclose(ours[key], np.broadcast_to(theirs, 3), atol=1e-6), key
    theirs = np.ravel(mi.traverse(mi.load_dict(sky))["radiance.value"])
    assert np.allclose(scene.environment[1], theirs, rtol=1e-4)


@pytest.mark.mitsuba
def test_transforms_as_mitsuba_builds_them(mi, tmp_path):
    """A rotation about an axis that is not a unit vector (Mitsuba does not
    normalise it) and a lookat without ``up``, against Mitsuba's matrices."""
    path = tmp_path / "t.xml"
    path.write_text("""<scene version="3.0.0">
    <shape type="rectangle" id="r">
        <transform name="to_world">
            <rotate value="0, 2, 0.5" angle="30"/>
            <scale x="2"/>
            <translate value="1 2 3"/>
        </transform>
    </shape>
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="1 2 3" target="0 0 0"/></transform>
    </sensor>
</scene>""")
    d = read_xml(path)
    theirs = mi.load_file(str(path))
    shape = next(s for s in theirs.shapes() if s.id() == "r")
    matrix = np.array(mi.traverse(shape)["to_world"].matrix, dtype=np.float64).reshape(4, 4)
    assert np.allclose(d["r"]["to_world"], matrix, atol=1e-5)
    cam = np.array(theirs.sensors()[0].world_transform().matrix, dtype=np.float64).reshape(4, 4)
    assert np.allclose(d["sensor_1"]["to_world"], cam, atol=1e-5)


def test_error_lines_name_the_right_object(tmp_path):
    """Ten unnamed shapes: an error in the tenth names its line, not the
    first's ("shape_10" starts with "shape_1")."""
    spheres = "\n".join('<shape type="sphere"/>' for _ in range(9))
    path = tmp_path / "ten.xml"
    path.write_text(f"""<scene version="3.0.0">
{spheres}
<shape type="sphere"><bsdf type="conductor"/></shape>
<sensor type="perspective"><float name="fov" value="40"/></sensor>
</scene>""")
    with pytest.raises(ValueError, match=r"ten.xml:11: shape_10.bsdf.type = 'conductor'"):
        mcs.Scene.from_mitsuba(path)
    path.write_text('<scene version="3.0.0"><shape type="sphere"><ref id="nothing"/></shape>'
                    '</scene>')
    with pytest.raises(ValueError, match="ten.xml:1: <ref>: no object with id 'nothing'"):
        read_xml(path)
    path.write_text('<scene version="3.0.0"><shape type="sphere"><float value="1"/></shape>'
                    '</scene>')
    with pytest.raises(ValueError, match="ten.xml:1: <float>: needs the attribute 'name'"):
        read_xml(path)


def test_a_single_mesh_file_has_no_second_mesh(tmp_path):
    path = tmp_path / "one.serialized"
    path.write_bytes(serialized_mesh(V1, F1))  # no table of offsets
    assert np.allclose(read_serialized(path)[0], V1, atol=1e-7)
    with pytest.raises(ValueError, match="shape_index = 1, but the file holds 1 mesh"):
        read_serialized(path, 1)


@pytest.mark.mitsuba
def test_mitsubas_cornell_box_renders_as_in_mitsuba(mi):
    """``mi.cornell_box()`` as Mitsuba 3.9 gives it (its gaussian filter,
    focus_distance on a pinhole, component_format, fov_axis "smaller",
    refs, an emitter with a bsdf, 256 x 256): mcsample's render of the dict
    is z-test-equal to Mitsuba's render of the same dict, whose region
    variances come from 16 independent renders (its filter splats samples
    onto neighbouring pixels); a light 5 % brighter is rejected."""
    skip_scalar(mi)
    d = mi.cornell_box()
    assert d["sensor"]["film"]["rfilter"]["type"] == "gaussian"
    ours = mcs.render(mcs.Scene.from_mitsuba(d), 64, seed=1)
    reference = mcs.mitsuba.render_runs(mi.load_dict(d), 16)
    result = stats.render_ztest(ours, reference)
    assert result.passed, result
    # Power: the light 5 % brighter is seen.
    light = d["light"]["emitter"]["radiance"]
    light["value"] = [1.05 * v for v in light["value"]]
    brighter = mcs.render(mcs.Scene.from_mitsuba(d), 64, seed=1)
    assert not stats.render_ztest(brighter, reference).passed
    d["sensor"]["film"]["component_format"] = "float16"
    with pytest.raises(ValueError, match="component_format must be 'float32'"):
        mcs.Scene.from_mitsuba(d)


#: ``mi.cornell_box()`` written by hand as a Mitsuba 3 XML file (refs,
#: transforms as translate / rotate / scale steps, lookat, the default
#: gaussian filter named explicitly).
CORNELL_XML = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="8"/></integrator>
  <sensor type="perspective">
    <string name="fov_axis" value="smaller"/>
    <float name="near_clip" value="0.001"/><float name="far_clip" value="100"/>
    <float name="focus_distance" value="1000"/><float name="fov" value="39.3077"/>
    <transform name="to_world"><lookat origin="0, 0, 3.9" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
    <film type="hdrfilm">
      <integer name="width" value="256"/><integer name="height" value="256"/>
      <rfilter type="gaussian"/>
      <string name="pixel_format" value="rgb"/><string name="component_format" value="float32"/>
    </film>
  </sensor>
  <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.885809, 0.698859, 0.666422"/></bsdf>
  <bsdf type="diffuse" id="green"><rgb name="reflectance" value="0.105421, 0.37798, 0.076425"/></bsdf>
  <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.570068, 0.0430135, 0.0443706"/></bsdf>
  <shape type="rectangle" id="light">
    <transform name="to_world"><scale x="0.23" y="0.19" z="0.19"/><rotate x="1" angle="90"/>
      <translate x="0" y="0.99" z="0.01"/></transform>
    <ref id="white"/>
    <emitter type="area"><rgb name="radiance" value="18.387, 13.9873, 6.75357"/></emitter>
  </shape>
  <shape type="rectangle" id="floor">
    <transform name="to_world"><rotate x="1" angle="-90"/><translate y="-1"/></transform>
    <ref id="white"/>
  </shape>
  <shape type="rectangle" id="ceiling">
    <transform name="to_world"><rotate x="1" angle="90"/><translate y="1"/></transform>
    <ref id="white"/>
  </shape>
  <shape type="rectangle" id="back">
    <transform name="to_world"><translate z="-1"/></transform><ref id="white"/>
  </shape>
  <shape type="rectangle" id="green-wall">
    <transform name="to_world"><rotate y="1" angle="-90"/><translate x="1"/></transform>
    <ref id="green"/>
  </shape>
  <shape type="rectangle" id="red-wall">
    <transform name="to_world"><rotate y="1" angle="90"/><translate x="-1"/></transform>
    <ref id="red"/>
  </shape>
  <shape type="cube" id="small-box">
    <transform name="to_world"><scale value="0.3"/><rotate y="1" angle="-17"/>
      <translate x="0.335" y="-0.7" z="0.38"/></transform>
    <ref id="white"/>
  </shape>
  <shape type="cube" id="large-box">
    <transform name="to_world"><scale x="0.3" y="0.61" z="0.3"/><rotate y="1" angle="18.25"/>
      <translate x="-0.33" y="-0.4" z="-0.28"/></transform>
    <ref id="white"/>
  </shape>
</scene>
"""


@pytest.mark.mitsuba
def test_cornell_box_written_as_xml_renders_as_in_mitsuba(mi, tmp_path):
    """The XML file above is ``mi.cornell_box()`` (its camera and every
    shape's vertices equal the dict's to 1e-5), and mcsample's render of
    the file is z-test-equal to Mitsuba's render of the same file (16
    independent renders: the gaussian filter splats)."""
    skip_scalar(mi)
    path = tmp_path / "cornell.xml"
    path.write_text(CORNELL_XML)
    ours, theirs = mcs.Scene.from_mitsuba(path), mcs.Scene.from_mitsuba(mi.cornell_box())
    assert np.allclose(ours.camera.to_world, theirs.camera.to_world, atol=1e-5)
    assert (ours.camera.rfilter, ours.integrator) == ("gaussian", theirs.integrator)
    for a, b in zip(ours.shapes, theirs.shapes, strict=True):
        assert a.key == b.key and np.allclose(a.vertices, b.vertices, atol=1e-5), a.key
    r = mcs.render(ours, 128, seed=2)
    result = stats.render_ztest(r, mcs.mitsuba.render_runs(mi.load_file(str(path)), 8))
    assert result.passed, result
