"""Every bad input gets its typed exception with a message naming the problem
(issue 2; SPEC and DEVELOPERS.md's list; issue 22's hardening). None crashes
the interpreter, and none escapes the exception hierarchy as a bare
TypeError, ValueError or UnicodeEncodeError."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

import penumbra
from penumbra import CameraError, LightError, MeshError, ParameterError, SceneError
from penumbra.scenes import box, ground_plane, ground_slab, sphere
from stress_scenes import NOT_YET

QUAD_V = np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], dtype=np.float32)
QUAD_F = np.array([[0, 2, 1], [0, 3, 2]])
CAMERA = penumbra.Camera(eye=(0, 4, 6), target=(0, 0, 0), width=32, height=32)
LIGHT = penumbra.SphereLight((0.3, 3, 0.2), 0.3, intensity=10)


PLANNED = [m for m in penumbra.methods(implemented_only=False) if m not in penumbra.methods()]


def quad(**kwargs: Any) -> penumbra.Mesh:
    args: dict[str, Any] = dict(vertices=QUAD_V, faces=QUAD_F, name="quad")
    args.update(kwargs)
    return penumbra.Mesh(args.pop("vertices"), args.pop("faces"), **args)


def render(meshes: Any = None, light: Any = None, camera: Any = None, method: str = "hard", **params: Any) -> Callable[[penumbra.Renderer], Any]:
    def run(renderer: penumbra.Renderer) -> Any:
        scene = penumbra.Scene(meshes if meshes is not None else [quad()], light or LIGHT, camera or CAMERA)
        return renderer.render(scene, method, **params)

    return run


def with_nan() -> np.ndarray:
    v = QUAD_V.copy()
    v[2, 1] = np.nan
    return v


def with_inf() -> np.ndarray:
    v = QUAD_V.copy()
    v[1, 0] = np.inf
    return v


def replaced(mesh: penumbra.Mesh, **attributes: Any) -> penumbra.Mesh:
    """The mesh with public attributes overwritten after construction (as a
    script may do), bypassing the constructor's checks."""
    for name, value in attributes.items():
        setattr(mesh, name, value)
    return mesh


def appended(scene: penumbra.Scene, item: Any) -> penumbra.Scene:
    scene.meshes.append(item)
    return scene


def with_attr(scene: penumbra.Scene, name: str, value: Any) -> penumbra.Scene:
    setattr(scene, name, value)
    return scene


def closed_box() -> penumbra.Mesh:
    return box((0, 1, 0), (0.5, 0.5, 0.5), name="box")


def empty_file() -> str:
    open("empty.obj", "w").close()
    return "empty.obj"


def text_file(name: str, text: str) -> str:
    with open(name, "w") as f:
        f.write(text)
    return name


def folder(name: str) -> str:
    os.mkdir(name)
    return name


def light_replaced(**attributes: Any) -> penumbra.Scene:
    """A scene whose light has public attributes overwritten after construction."""
    light = penumbra.SphereLight((0.3, 3, 0.2), 0.3, intensity=10)
    for name, value in attributes.items():
        setattr(light, name, value)
    return penumbra.Scene([quad()], light, CAMERA)


def scaled_default_scene(scale: float) -> penumbra.Scene:
    """sphere_on_plane with every coordinate and the light's radius times ``scale``."""
    base = penumbra.scenes.get("sphere_on_plane", width=16, height=16)
    meshes = [
        penumbra.Mesh(m.vertices, m.faces, transform=np.diag([scale, scale, scale, 1.0]) @ m.transform.astype(np.float64), name=m.name)
        for m in base.meshes
    ]
    light = penumbra.SphereLight(base.light.center.astype(np.float64) * scale, base.light.radius * scale, intensity=base.light.intensity)
    assert base.camera is not None
    c = base.camera
    camera = penumbra.Camera(np.asarray(c.eye) * scale, np.asarray(c.target) * scale, c.up, c.fov_y, c.width, c.height)
    return penumbra.Scene(meshes, light, camera)


# (id, action, exception, words the message must contain)
CASES: list[tuple[str, Callable[..., Any], type[Exception], list[str]]] = [
    # Meshes
    ("nan_vertex", render([quad(vertices=with_nan())]), MeshError, ["quad", "vertex 2", "NaN"]),
    ("inf_vertex", render([quad(vertices=with_inf())]), MeshError, ["vertex 1", "infinite"]),
    ("overflow_to_inf", render([quad(vertices=QUAD_V.astype(np.float64) * 1e39)]), MeshError, ["infinite"]),
    ("vertices_shape", lambda r: quad(vertices=QUAD_V[:, :2]), MeshError, ["vertices", "shape (N, 3)", "(4, 2)"]),
    ("vertices_dtype", lambda r: quad(vertices=[["a", "b", "c"]] * 4), MeshError, ["vertices", "numeric"]),
    ("vertices_complex", lambda r: quad(vertices=QUAD_V.astype(complex)), MeshError, ["vertices", "real"]),
    ("faces_float", lambda r: quad(faces=QUAD_F.astype(float)), MeshError, ["faces", "integers"]),
    ("faces_shape", lambda r: quad(faces=[[0, 1, 2, 3]]), MeshError, ["faces", "(M, 3)"]),
    ("face_out_of_range", render([quad(faces=[[0, 1, 7]])]), MeshError, ["face 0", "out of range", "4 vertices"]),
    ("face_negative", lambda r: quad(faces=[[0, -1, 2]]), MeshError, ["negative index"]),
    ("empty_mesh", render([quad(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), int))]), MeshError, ["no vertices"]),
    ("no_faces", render([quad(faces=np.zeros((0, 3), int))]), MeshError, ["no faces"]),
    ("all_degenerate", render([quad(faces=[[0, 1, 1], [2, 2, 2]])]), MeshError, ["degenerate"]),
    ("collinear_face", render([quad(vertices=[[0, 0, 0], [1, 0, 0], [2, 0, 0]], faces=[[0, 1, 2]])]), MeshError, ["degenerate"]),
    ("albedo_range", render([quad(albedo=1.5)]), MeshError, ["albedo", "[0, 1]"]),
    ("albedo_nan", render([quad(albedo=(0.5, np.nan, 0.5))]), MeshError, ["albedo"]),
    ("albedo_shape", lambda r: quad(albedo=(0.5, 0.5)), MeshError, ["albedo", "shape (3)"]),
    ("object_id_negative", lambda r: quad(object_id=-1), MeshError, ["object_id", ">= 0"]),
    ("object_id_type", lambda r: quad(object_id=1.5), MeshError, ["object_id", "integer"]),
    ("transform_singular", render([quad(transform=np.diag([1, 0, 1, 1]))]), MeshError, ["singular"]),
    ("transform_projective", render([quad(transform=[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0.5, 1]])]), MeshError, ["affine"]),
    ("transform_nan", render([quad(transform=np.full((4, 4), np.nan))]), MeshError, ["transform", "NaN"]),
    ("transform_shape", lambda r: quad(transform=np.eye(3)), MeshError, ["transform", "(4, 4)"]),
    ("normals_count", render([quad(normals=np.ones((3, 3)))]), MeshError, ["3 normals for 4 vertices"]),
    ("normals_zero", render([quad(normals=np.zeros((4, 3)))]), MeshError, ["normal 0", "zero"]),
    ("trimesh_scene", lambda r: penumbra.Mesh.from_trimesh(__import__("trimesh").Scene()), MeshError, ["trimesh.Scene"]),
    ("unreadable_mesh_file", lambda r: penumbra.scenes.from_mesh(__file__), MeshError, ["cannot read mesh file"]),
    # Lights
    ("negative_radius", lambda r: penumbra.SphereLight((0, 3, 0), -0.5, intensity=1), LightError, ["radius", ">= 0"]),
    ("nan_radius", lambda r: penumbra.SphereLight((0, 3, 0), float("nan"), intensity=1), LightError, ["radius"]),
    ("radius_type", lambda r: penumbra.SphereLight((0, 3, 0), "big", intensity=1), LightError, ["radius", "real number"]),
    ("light_center_nan", render(light=penumbra.SphereLight((0, np.nan, 0), 0.3, intensity=1)), LightError, ["center", "finite"]),
    ("negative_intensity", render(light=penumbra.SphereLight((0, 3, 0), 0.3, intensity=-1)), LightError, ["intensity", ">= 0"]),
    ("radiance_of_point_light", lambda r: penumbra.SphereLight((0, 3, 0), 0.0, radiance=1), LightError, ["radius-0", "intensity"]),
    ("radiance_and_intensity", lambda r: penumbra.SphereLight((0, 3, 0), 1.0, radiance=1, intensity=1), LightError, ["exactly one"]),
    ("light_intersects_mesh", render(light=penumbra.SphereLight((0, 0.2, 0), 0.3, intensity=1)), SceneError, ["intersects mesh 'quad'"]),
    ("point_light_on_surface", render(light=penumbra.SphereLight((0.5, 0, 0.5), 0.0, intensity=1)), SceneError, ["intersects"]),
    # Casters above and below the light (the floor under everything casts nothing).
    ("geometry_surrounds_light_one_frustum", render([sphere((0, 1, 0), 0.5), sphere((0, -1, 0), 0.5)], light=penumbra.SphereLight((0, 0, 0), 0.1, intensity=1), projection="frustum"), SceneError, ["surrounds the light", "projection='auto'"]),
    # Cameras and images
    ("zero_width", lambda r: CAMERA.with_size(0, 32), CameraError, ["at least 1x1", "0x32"]),
    ("zero_height", lambda r: CAMERA.with_size(32, 0), CameraError, ["0"]),
    ("negative_width", lambda r: CAMERA.with_size(-5, 32), CameraError, ["width"]),
    ("width_type", lambda r: CAMERA.with_size(32.5, 32), CameraError, ["width", "integer"]),
    ("huge_image", render(camera=CAMERA.with_size(100_000, 100_000)), CameraError, ["exceeds"]),
    ("fov_zero", render(camera=penumbra.Camera((0, 4, 6), (0, 0, 0), fov_y=0, width=8, height=8)), CameraError, ["fov_y"]),
    ("fov_180", render(camera=penumbra.Camera((0, 4, 6), (0, 0, 0), fov_y=180, width=8, height=8)), CameraError, ["fov_y"]),
    ("eye_is_target", render(camera=penumbra.Camera((0, 4, 6), (0, 4, 6), width=8, height=8)), CameraError, ["coincide"]),
    ("up_parallel", render(camera=penumbra.Camera((0, 4, 0), (0, 0, 0), up=(0, 1, 0), width=8, height=8)), CameraError, ["parallel"]),
    ("eye_nan", lambda r: penumbra.Camera((0, np.nan, 6), (0, 0, 0)), CameraError, ["eye", "finite"]),
    ("no_camera", lambda r: r.render(penumbra.Scene([quad()], LIGHT)), CameraError, ["no camera"]),
    # Scenes
    ("no_meshes", render([]), SceneError, ["no meshes"]),
    ("not_a_mesh", lambda r: penumbra.Scene([QUAD_V], LIGHT, CAMERA), SceneError, ["meshes[0]", "penumbra.Mesh"]),
    ("not_a_light", lambda r: penumbra.Scene([quad()], (0, 3, 0), CAMERA), SceneError, ["light"]),
    ("negative_ambient", lambda r: r.render(penumbra.Scene([quad()], LIGHT, CAMERA, ambient=-1.0)), SceneError, ["ambient"]),
    ("not_a_scene", lambda r: r.render("sphere_on_plane"), SceneError, ["penumbra.Scene"]),
    ("unknown_scene", lambda r: penumbra.scenes.get("teapot"), ParameterError, ["unknown scene", "sphere_on_plane"]),
    # Methods and parameters
    ("unknown_method", render(method="magic"), ParameterError, ["unknown method 'magic'", "hard"]),
    ("method_not_implemented", render(method=NOT_YET or "magic"), ParameterError, [f"'{NOT_YET}'", "not implemented"] if NOT_YET else ["unknown method"]),
    ("unknown_parameter", render(kernel=3), ParameterError, ["kernel", "map_size"]),
    ("map_size_too_small", render(map_size=8), ParameterError, ["map_size", "[16, 16384]", "8"]),
    ("map_size_wrong_type", render(map_size="big"), ParameterError, ["map_size", "integer"]),
    ("map_size_float", render(map_size=512.0), ParameterError, ["map_size", "integer"]),
    ("bias_unknown", render(bias="magic"), ParameterError, ["bias", "slope", "second_depth"]),
    ("offset_negative", render(normal_offset=-1.0), ParameterError, ["normal_offset"]),
    ("offset_nan", render(normal_offset=float("nan")), ParameterError, ["normal_offset"]),
    ("param_unsupported_type", render(map_size=[1, 2]), ParameterError, ["map_size", "unsupported type"]),
    ("timing_mode", lambda r: penumbra.Renderer(timing="sometimes"), ParameterError, ["timing"]),
    # Outputs
    ("image_extension", lambda r: penumbra.write_image("out.bmp", np.zeros((2, 2), np.float32)), ParameterError, [".png (sRGB 8-bit), .exr (linear float), .npy (the array as is); got .bmp"]),
    ("image_shape", lambda r: penumbra.write_image("out.png", np.zeros((2, 2, 4), np.float32)), ParameterError, ["(H, W)"]),
    ("exr_nan", lambda r: penumbra.write_image("out.exr", np.full((2, 2), np.nan, np.float32)), ParameterError, ["non-finite"]),
    # Issue 8: more of the matrix (dtype, shape, NaN/Inf, ranges, geometry around the camera and light)
    ("vertices_3d_array", lambda r: quad(vertices=QUAD_V[:, :, None]), MeshError, ["vertices", "shape (N, 3)"]),
    ("vertices_scalar", lambda r: quad(vertices=1.0), MeshError, ["vertices", "shape (N, 3)"]),
    ("vertices_object_none", lambda r: quad(vertices=[[0, None, 0]] * 4), MeshError, ["vertices", "numeric"]),
    ("vertices_ragged", lambda r: quad(vertices=[[0, 0, 0], [1, 0]]), MeshError, ["vertices"]),
    ("vertices_float16_inf", render([quad(vertices=np.full((4, 3), np.inf, dtype=np.float16))]), MeshError, ["infinite"]),
    ("vertices_replaced_after_construction", render([replaced(quad(), vertices=QUAD_V.astype(np.float64)[:, :2])]), MeshError, ["vertices", "shape (N, 3)"]),
    ("faces_bool", lambda r: quad(faces=QUAD_F.astype(bool)), MeshError, ["faces", "integers"]),
    ("faces_beyond_uint32", lambda r: quad(faces=np.array([[0, 1, 2**33]], dtype=np.int64)), MeshError, ["exceeds uint32"]),
    ("faces_replaced_after_construction", render([replaced(quad(), faces=[[0, 1, 9]])]), MeshError, ["face 0", "out of range"]),
    ("faces_string", lambda r: quad(faces="0 1 2"), MeshError, ["faces"]),
    ("normals_nan", render([quad(normals=np.full((4, 3), np.nan))]), MeshError, ["normal 0"]),
    ("normals_shape", lambda r: quad(normals=np.ones((4, 2))), MeshError, ["normals", "shape (N, 3)"]),
    ("transform_inf", render([quad(transform=np.diag([1, np.inf, 1, 1]))]), MeshError, ["transform", "infinite"]),
    ("transform_overflows_vertices", render([quad(transform=np.diag([1e38, 1e38, 1e38, 1]) @ np.diag([10, 10, 10, 1]))]), MeshError, ["infinite"]),
    ("name_and_mesh_in_message", render([quad(name="wing", vertices=with_nan())]), MeshError, ["'wing'"]),
    ("light_center_shape", lambda r: penumbra.SphereLight((0, 3), 0.3, intensity=1), LightError, ["center", "shape (3)"]),
    ("light_center_inf", render(light=penumbra.SphereLight((0, np.inf, 0), 0.3, intensity=1)), LightError, ["center", "finite"]),
    ("radius_inf", lambda r: penumbra.SphereLight((0, 3, 0), float("inf"), intensity=1), LightError, ["radius", "finite"]),
    ("radius_bool", lambda r: penumbra.SphereLight((0, 3, 0), True, intensity=1), LightError, ["radius", "real number"]),
    ("intensity_nan", render(light=penumbra.SphereLight((0, 3, 0), 0.3, intensity=(1, np.nan, 1))), LightError, ["intensity", "finite"]),
    ("radiance_overflows_intensity", render(light=penumbra.SphereLight((0, 1e19, 0), 1e18, radiance=1e30)), LightError, ["intensity", "finite"]),
    ("huge_radius_swallows_scene", render(light=penumbra.SphereLight((0, 3, 0), 1e6, intensity=1)), SceneError, ["intersects mesh 'quad'"]),
    ("light_inside_closed_box_one_frustum", render([box((0, 1, 0), (2, 2, 2), name="room")], light=penumbra.SphereLight((0, 1, 0), 0.2, intensity=1), method="pvm", projection="frustum"), SceneError, ["surrounds the light"]),
    ("projection_unknown", render(projection="sphere"), ParameterError, ["projection", "'auto', 'frustum', 'cube'"]),
    ("fov_negative", render(camera=penumbra.Camera((0, 4, 6), (0, 0, 0), fov_y=-10, width=8, height=8)), CameraError, ["fov_y"]),
    ("fov_nan", render(camera=penumbra.Camera((0, 4, 6), (0, 0, 0), fov_y=float("nan"), width=8, height=8)), CameraError, ["fov_y"]),
    ("fov_string", lambda r: penumbra.Camera((0, 4, 6), (0, 0, 0), fov_y="wide"), CameraError, ["fov_y", "real number"]),
    ("up_zero", render(camera=penumbra.Camera((0, 4, 6), (0, 0, 0), up=(0, 0, 0), width=8, height=8)), CameraError, ["up vector is zero"]),
    ("target_inf", lambda r: penumbra.Camera((0, 4, 6), (0, np.inf, 0)), CameraError, ["target", "finite"]),
    ("width_beyond_int32", lambda r: CAMERA.with_size(2**40, 8), CameraError, ["width", "2^31"]),
    ("one_pixel_by_huge", render(camera=CAMERA.with_size(1, 2**31)), CameraError, ["exceeds"]),
    ("camera_override_wrong_type", lambda r: r.render(penumbra.Scene([quad()], LIGHT, CAMERA), camera="front"), CameraError, ["penumbra.Camera"]),
    ("mesh_appended_after_construction", lambda r: r.render(appended(penumbra.Scene([quad()], LIGHT, CAMERA), "box")), SceneError, ["meshes[1]", "penumbra.Mesh"]),
    ("light_replaced_after_construction", lambda r: r.render(with_attr(penumbra.Scene([quad()], LIGHT, CAMERA), "light", None)), SceneError, ["light"]),
    ("ambient_nan", lambda r: r.render(penumbra.Scene([quad()], LIGHT, CAMERA, ambient=np.nan)), SceneError, ["ambient"]),
    ("method_not_a_string", render(method=None), ParameterError, ["method", "string"]),
    ("method_wrong_case", render(method="PVM"), ParameterError, ["unknown method 'PVM'"]),
    # A SPEC method no one has implemented yet (skipped when all are).
    *[("method_not_implemented", render(method=m), ParameterError, ["not implemented"]) for m in PLANNED[:1]],
    ("param_of_another_method", render(method="pcf", s_e=0.5), ParameterError, ["s_e", "pcf"]),
    ("param_none", render(map_size=None), ParameterError, ["map_size", "unsupported type"]),
    ("param_int_overflow", render(map_size=2**80), ParameterError, ["map_size", "integer"]),
    ("param_inf", render(method="pvmf", s_p=float("inf")), ParameterError, ["s_p"]),
    ("map_size_huge", render(map_size=10**6), ParameterError, ["map_size", "[16, 16384]"]),
    ("pvmf_s_e_zero", render(method="pvmf", s_e=0.0), ParameterError, ["s_e", "(0, 1]"]),
    ("pvmf_s_e_above_one", render(method="pvmf", s_e=1.5), ParameterError, ["s_e"]),
    ("pvmf_n_pcf_zero", render(method="pvmf", n_pcf=0), ParameterError, ["n_pcf", "[1, 32]"]),
    ("pvmf_seed_negative", render(method="pvmf", seed=-1), ParameterError, ["seed"]),
    ("pvmf_kernel_unknown", render(method="pvmf", kernel="hexagon"), ParameterError, ["kernel", "square", "disk"]),
    ("pvm_falloff_string", render(method="pvm", falloff="yes"), ParameterError, ["falloff", "bool"]),
    ("pvm_open_edges_unknown", render(method="pvm", open_edges="ignore"), ParameterError, ["open_edges", "silhouette"]),
    # Open and non-manifold casters render by default (docs/real_meshes.md); open_edges="error" refuses them.
    ("pvm_open_caster", render(method="pvm", open_edges="error"), MeshError, ["'quad'", "not closed", "open_edges='silhouette'"]),
    # Three faces on the quad's diagonal (a doubled face would be one face, issue 27).
    ("pvm_non_manifold_caster", render([closed_box(), quad(vertices=np.vstack([QUAD_V, [[0.0, 1.5, 0.9]]]), faces=np.vstack([QUAD_F, [[0, 2, 4]]]))], method="pvm", open_edges="error"), MeshError, ["'quad'", "not a 2-manifold", "open_edges='silhouette'"]),
    ("pvmf_open_caster", render(method="pvmf", open_edges="error"), MeshError, ["not closed"]),
    ("result_unknown_image", lambda r: render()(r).save("x.png", image="albedo"), ParameterError, ["albedo"]),
    ("write_into_missing_folder", lambda r: penumbra.write_image("no/such/dir/out.png", np.zeros((2, 2), np.float32)), penumbra.PenumbraIOError, ["no/such/dir/out.png"]),
    ("mesh_file_empty", lambda r: penumbra.scenes.from_mesh(empty_file()), MeshError, ["empty.obj"]),
    ("mesh_file_is_a_folder", lambda r: penumbra.scenes.from_mesh("."), MeshError, ["cannot read mesh file"]),
    ("scene_size_zero", lambda r: r.render(penumbra.scenes.get("sphere_on_plane", width=0, height=8)), CameraError, ["at least 1x1"]),
    # Issue 22: huge coordinates (item 5) name the range, not "180 degrees off the axis".
    ("scene_scaled_by_1e20", lambda r: r.render(scaled_default_scene(1e20)), penumbra.InvalidInputError, ["supported range", "float32", "scale the scene down"]),
    ("sphere_of_1e38", render([ground_slab(), sphere((0, 1e38, 0), 1e37)]), MeshError, ["'sphere'", "vertex", "supported range", "float32"]),
    ("light_beyond_range", render(light=penumbra.SphereLight((0, 3e18, 0), 0.3, intensity=1)), LightError, ["supported range"]),
    ("camera_beyond_range", render(camera=penumbra.Camera((0, 4e18, 6), (0, 0, 0), width=8, height=8)), CameraError, ["eye", "supported range"]),
    ("scene_below_smallest_extent", render([quad(transform=np.diag([1e-20, 1e-20, 1e-20, 1]))], light=penumbra.SphereLight((0, 1e-19, 0), 0.0, intensity=1e-40)), SceneError, ["spans only", "scale the scene up"]),
    # Item 6: reference's refusal (with one frustum per sample, as every method's was before
    # cube maps) says which sample and what to do.
    ("reference_sample_outside_one_frustum", render([ground_slab()], light=penumbra.SphereLight((0, 1.4, 0), 0.3, intensity=10), method="reference", n_samples=16, map_size=256, projection="frustum"), SceneError, ["method 'reference'", "light sample", " of ", "degrees off", "projection='auto'", "smaller radius"]),
    ("adaptive_sample_outside_one_frustum", render([ground_slab()], light=penumbra.SphereLight((0, 1.4, 0), 0.3, intensity=10), method="adaptive", max_depth=1, map_size=256, projection="frustum"), SceneError, ["method 'adaptive'", "light sample", " of 9", "degrees off", "projection='auto'", "smaller radius"]),
    # Item 8: light attributes replaced after construction are checked again.
    ("light_center_replaced_none", lambda r: r.render(light_replaced(center=None)), LightError, ["light center", "numeric"]),
    ("light_intensity_replaced_shape", lambda r: r.render(light_replaced(intensity=[1, 2])), LightError, ["light intensity", "shape (3)"]),
    ("light_radius_replaced_string", lambda r: r.render(light_replaced(radius="0.5")), LightError, ["light radius", "real number", "'0.5'"]),
    ("light_radius_replaced_negative", lambda r: r.render(light_replaced(radius=-1.0)), LightError, ["light radius", ">= 0"]),
    # Item 9: object ids outside int32, at construction and after replacement.
    ("object_id_2_63", lambda r: quad(object_id=2**63), MeshError, ["object_id", "2147483647", "9223372036854775808"]),
    ("object_id_uint64_max", lambda r: quad(object_id=np.uint64(2**64 - 1)), MeshError, ["object_id", "18446744073709551615"]),
    ("object_id_replaced_2_40", render([replaced(quad(), object_id=2**40)]), MeshError, ["object_id", "2147483647"]),
    # Item 10: no bare TypeError, ValueError or UnicodeEncodeError.
    ("scene_meshes_none", lambda r: penumbra.Scene(None, LIGHT, CAMERA), SceneError, ["meshes", "NoneType"]),
    ("scene_meshes_int", lambda r: penumbra.Scene(5, LIGHT, CAMERA), SceneError, ["meshes", "int"]),
    ("timing_none", lambda r: penumbra.Renderer(timing=None), ParameterError, ["timing", "'auto' or 'cpu'", "None"]),
    ("scene_name_list", lambda r: penumbra.scenes.get(["x"]), ParameterError, ["unknown scene", "['x']"]),
    ("sweep_params_int", lambda r: penumbra.sweep(penumbra.Scene([quad()], LIGHT, CAMERA), "hard", params=5, renderer=r, progress=False), ParameterError, ["params must be", "int"]),
    ("sweep_scenes_int", lambda r: penumbra.sweep(5, "hard", renderer=r, progress=False), SceneError, ["scenes must be", "int"]),
    ("write_image_path_none", lambda r: penumbra.write_image(None, np.zeros((2, 2), np.float32)), ParameterError, ["path", "NoneType"]),
    ("write_image_string_image", lambda r: penumbra.write_image("a.png", "abc"), ParameterError, ["image", "numeric", "<U3"]),
    ("mesh_name_lone_surrogate", lambda r: quad(name="wing\udc80"), MeshError, ["mesh name", "not valid Unicode"]),
    ("mesh_name_replaced_surrogate", render([replaced(quad(), name="wing\udc80")]), MeshError, ["mesh name", "not valid Unicode"]),
    # Item 11: parameter messages as Python writes the value, integers beyond int64 as integers.
    ("param_str_for_int", render(map_size="abc"), ParameterError, ["map_size", "got str 'abc'"]),
    ("param_float_for_int", render(map_size=256.0), ParameterError, ["map_size", "got float 256.0"]),
    ("param_bool_for_float", render(normal_offset=True), ParameterError, ["normal_offset", "got bool True"]),
    ("param_int_beyond_int64", render(method="pcf", seed=2**63), ParameterError, ["seed", "an integer in [0, 4294967295]", "got int 9223372036854775808"]),
    ("param_uint64_beyond_int64", render(method="pcf", seed=np.uint64(2**64 - 1)), ParameterError, ["seed", "got int 18446744073709551615"]),
    ("param_float_param_given_huge_int", render(method="pcf", kernel=2**70), ParameterError, ["kernel", "a number in", "got int 1180591620717411303424"]),
    # Item 12: accepted silently before.
    ("intermediates_string", render(intermediates="no"), ParameterError, ["intermediates", "True or False", "'no'"]),
    ("intermediates_int", render(intermediates=1), ParameterError, ["intermediates", "True or False"]),
    ("pass_cache_string", lambda r: penumbra.Renderer(pass_cache="no"), ParameterError, ["pass_cache", "True or False", "'no'"]),
    ("png_nan", lambda r: penumbra.write_image("out.png", np.full((2, 2), np.nan, np.float32)), ParameterError, ["non-finite", "NaN", "row 0, column 0"]),
    ("png_inf", lambda r: penumbra.write_image("out.png", np.array([[0.5, np.inf]], np.float32)), ParameterError, ["non-finite", "row 0, column 1"]),
    ("png_object_dtype", lambda r: penumbra.write_image("out.png", np.array([[1.0, None]], dtype=object)), ParameterError, ["numeric", "object"]),
    ("npy_object_dtype", lambda r: penumbra.write_image("out.npy", np.array([[1.0, None]], dtype=object)), ParameterError, ["numeric", "object"]),
    ("sweep_keep_unknown_image", lambda r: penumbra.sweep(penumbra.Scene([quad()], LIGHT, CAMERA), "hard", keep_images=["nope"], renderer=r, progress=False), ParameterError, ["keep_images", "nope", "radiance"]),
    ("faces_timedelta", lambda r: quad(faces=QUAD_F.astype("timedelta64[s]")), MeshError, ["faces", "integers", "timedelta64"]),
    ("camera_with_size_0_0", lambda r: CAMERA.with_size(0, 0), CameraError, ["at least 1x1", "0x0"]),
    # Item 7: .npy output errors are PenumbraIOError, as .png's are.
    ("npy_into_missing_folder", lambda r: penumbra.write_image("no/such/dir/out.npy", np.zeros((2, 2), np.float32)), penumbra.PenumbraIOError, ["no/such/dir/out.npy"]),
    ("npy_onto_a_folder", lambda r: penumbra.write_image(folder("out.npy"), np.zeros((2, 2), np.float32)), penumbra.PenumbraIOError, ["out.npy"]),
    # Item 13: a mesh file with a vertex beyond float32's range names it.
    ("mesh_file_vertex_1e39", lambda r: penumbra.scenes.from_mesh(text_file("far.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1e39\nf 1 2 3\n")), MeshError, ["far.obj", "vertex 2", "1e+39", "float32"]),
]


@pytest.mark.parametrize("action, error, words", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_raises_a_typed_error(renderer: penumbra.Renderer, action: Callable[..., Any], error: type[Exception], words: list[str], tmp_path: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(error) as info:
        action(renderer)
    message = str(info.value)
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"
    assert isinstance(info.value, penumbra.PenumbraError)
    if issubclass(error, penumbra.InvalidInputError):
        assert isinstance(info.value, ValueError), "input errors are ValueErrors too"
    else:
        assert isinstance(info.value, OSError), "output errors are OSErrors"


def test_renderer_still_works_after_errors(renderer: penumbra.Renderer) -> None:
    for _, action, error, _ in CASES[:10]:
        with pytest.raises(error):
            action(renderer)
    result = render()(renderer)
    assert np.isfinite(result.radiance).all() and result.visibility.max() == 1.0


# Issue 22, beyond the table above.


@pytest.mark.parametrize("target", ["missing/out.npy", "folder.npy"])
def test_cli_npy_output_errors_exit_2_with_one_line(target: str, tmp_path: Path) -> None:
    """Item 7: the README promises exit 2 and one line for every error."""
    (tmp_path / "folder.npy").mkdir()
    done = subprocess.run(
        [sys.executable, "-m", "penumbra", "render", "--width", "8", "--height", "8", "--param", "map_size=256", "-o", target],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
    )
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("penumbra: error: ") and target in lines[0], done.stderr


def test_light_attributes_replaced_with_other_dtypes_are_coerced(renderer: penumbra.Renderer) -> None:
    """Item 8: a float64 centre (or a list, or an int radius) renders as the
    float32 original does, as mesh attributes already did."""
    original = penumbra.Scene([quad()], penumbra.SphereLight((0.3, 3, 0.2), 0.5, intensity=10), CAMERA)
    expected = renderer.render(original, map_size=256).visibility
    replaced_light = light_replaced(center=np.array([0.3, 3.0, 0.2]), intensity=[10, 10, 10])
    replaced_light.light.radius = 0.5
    np.testing.assert_array_equal(renderer.render(replaced_light, map_size=256).visibility, expected)


def test_write_image_takes_bytes_paths(tmp_path: Path) -> None:
    """Item 10: a bytes path is a path (os.fsdecode), for every format."""
    for name in ("a.png", "a.exr", "a.npy"):
        path = os.fsencode(tmp_path / name)
        penumbra.write_image(path, np.full((2, 3), 0.5, np.float32))
        assert (tmp_path / name).stat().st_size > 0


@pytest.mark.parametrize(
    "call, error, words",
    [
        (lambda core, r: core.Renderer(timing=5), ParameterError, ["timing"]),
        (lambda core, r: core.Renderer(pass_cache=1), ParameterError, ["pass_cache", "True or False"]),
        (lambda core, r: r._core.render(None, None, "hard", {}), SceneError, ["scene"]),
        (lambda core, r: r._core.render(core_scene(), None, "hard", {}), CameraError, ["camera"]),
        (lambda core, r: r._core.render(core_scene(vertices=QUAD_V.astype(np.float64)), CAMERA._core_value(), "hard", {}), MeshError, ["meshes[0]", "vertices"]),
        (lambda core, r: r._core.render(core_scene(vertices=QUAD_V[:, :2].copy()), CAMERA._core_value(), "hard", {}), MeshError, ["'quad'", "vertices", "(N, 3)"]),
        (lambda core, r: r._core.render(core_scene(), CAMERA._core_value(), 5, {}), ParameterError, ["method"]),
        (lambda core, r: r._core.render(core_scene(), CAMERA._core_value(), "hard", [("map_size", 256)]), ParameterError, ["params must be a dict"]),
        (lambda core, r: r._core.render(core_scene(), CAMERA._core_value(), "hard", {1: 256}), ParameterError, ["parameter name"]),
        (lambda core, r: r._core.render(core_scene(), CAMERA._core_value(), "pcf", {"seed": 2**63}), ParameterError, ["seed", "integer 9223372036854775808", "64-bit"]),
        (lambda core, r: core.write_image(None, np.zeros((2, 2), np.float32)), ParameterError, ["path"]),
        (lambda core, r: core.write_image("a.png", np.zeros((2, 2), np.float64)), ParameterError, ["image", "float32"]),
    ],
)
def test_the_binding_raises_typed_errors_only(renderer: penumbra.Renderer, call: Callable[..., Any], error: type[Exception], words: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 16 and item 10: conversion errors in penumbra._core itself (the
    values penumbra.scene builds, handed in wrong) are typed, not TypeError."""
    from penumbra import _core

    monkeypatch.chdir(tmp_path)
    with pytest.raises(error) as info:
        call(_core, renderer)
    for word in words:
        assert word in str(info.value), f"{word!r} not in {info.value}"


def core_scene(**mesh: Any) -> Any:
    from dataclasses import replace as replace_fields

    value = penumbra.Scene([quad()], LIGHT, CAMERA)._core_value()
    return replace_fields(value, meshes=[replace_fields(value.meshes[0], **mesh)])


def test_mesh_file_beyond_float32_warns_nothing(tmp_path: Path) -> None:
    """Item 13: the error names the coordinate; trimesh's cast warning does not reach the caller."""
    path = text_file(str(tmp_path / "far.obj"), "v 0 0 0\nv 1 0 0\nv 0 0 1e39\nf 1 2 3\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(MeshError, match="vertex 2"):
            penumbra.scenes.from_mesh(path)
    assert not caught, [str(w.message) for w in caught]


def test_the_scene_reference_refuses_renders_with_every_other_method(renderer: penumbra.Renderer) -> None:
    """Item 6: with one frustum per map, the light's centre sees the slab
    within it and only reference's samples on the light's sphere do not
    (its refusal above); each remedy the message names works here."""
    scene = penumbra.Scene([ground_slab()], penumbra.SphereLight((0, 1.4, 0), 0.3, intensity=10), CAMERA)
    for method in penumbra.methods():
        # Every shadow-map method but those with maps from points on the
        # light, reference and adaptive (raytraced has no map).
        if method not in ("reference", "adaptive") and "projection" in penumbra.method_info(method).defaults():
            renderer.render(scene, method, map_size=256, projection="frustum")
    renderer.render(scene, "reference", n_samples=16, map_size=256)  # projection="auto": cube faces
    assert renderer.render(scene, "adaptive", max_depth=1, map_size=256).stats["cube_maps"] > 0
    renderer.render(scene.with_light(scene.light.with_radius(0.1)), "reference", n_samples=16, map_size=256, projection="frustum")
    renderer.render(scene.with_light(penumbra.SphereLight((0, 1.8, 0), 0.3, intensity=10)), "reference", n_samples=16, map_size=256, projection="frustum")
