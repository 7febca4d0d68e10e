//! pyo3 bindings of penumbra-core, and nothing else: conversions between
//! numpy/Python values and core types, error mapping, and releasing the GIL
//! around rendering and readback. The Python API proper is `python/penumbra`.
//!
//! Scenes and cameras arrive as the typed values of `penumbra/scene.py`
//! (`CoreScene`, `CoreMesh`, `CoreLight`, `CoreCamera`), read attribute by
//! attribute by name. Every conversion error is one of `penumbra.errors`'
//! classes, naming what could not be converted: never a bare `TypeError`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use penumbra_core as core;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString};

// The exception hierarchy is defined in Python (`penumbra/errors.py`) so that
// input errors can subclass both PenumbraError and ValueError.
pyo3::import_exception!(penumbra.errors, MeshError);
pyo3::import_exception!(penumbra.errors, LightError);
pyo3::import_exception!(penumbra.errors, CameraError);
pyo3::import_exception!(penumbra.errors, SceneError);
pyo3::import_exception!(penumbra.errors, ParameterError);
pyo3::import_exception!(penumbra.errors, GpuUnavailableError);
pyo3::import_exception!(penumbra.errors, GpuError);
pyo3::import_exception!(penumbra.errors, GpuFeatureError);
pyo3::import_exception!(penumbra.errors, PenumbraIOError);
pyo3::import_exception!(penumbra.errors, InternalError);

/// Maps each core error to its Python exception class.
fn to_py(e: core::Error) -> PyErr {
    let message = e.to_string();
    match e {
        core::Error::InvalidMesh { .. } => MeshError::new_err(message),
        core::Error::InvalidLight(_) => LightError::new_err(message),
        core::Error::InvalidCamera(_) => CameraError::new_err(message),
        core::Error::InvalidScene(_) => SceneError::new_err(message),
        core::Error::InvalidParameter(_) => ParameterError::new_err(message),
        core::Error::GpuUnavailable(_) => GpuUnavailableError::new_err(message),
        core::Error::MissingFeature(_) => GpuFeatureError::new_err(message),
        core::Error::Gpu(_) | core::Error::OutOfMemory(_) => GpuError::new_err(message),
        core::Error::Io(_) => PenumbraIOError::new_err(message),
    }
}

/// A constructor of one of the exception classes above.
type ErrorClass = fn(String) -> PyErr;

/// `what: <the conversion error and its causes>` as `class`: pyo3's own
/// conversion errors (a `TypeError` whose cause says which attribute failed)
/// become the typed error of what was being converted.
fn conversion_error(py: Python<'_>, class: ErrorClass, what: &str, e: PyErr) -> PyErr {
    let mut message = format!("{what}: {}", e.value(py));
    let mut cause = e.cause(py);
    while let Some(c) = cause {
        message.push_str(&format!(": {}", c.value(py)));
        cause = c.cause(py);
    }
    class(message)
}

/// Extracts `T` from `obj`, any failure raised as `class` naming `what`.
fn extract<'a, 'py, T>(obj: &'a Bound<'py, PyAny>, class: ErrorClass, what: &str) -> PyResult<T>
where
    T: FromPyObject<'a, 'py>,
{
    obj.extract::<T>().map_err(|e| conversion_error(obj.py(), class, what, e.into()))
}

/// A Python `bool` (or numpy bool) only: `"no"` or `1` is refused, not truthy.
fn strict_bool(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<bool> {
    let type_name = obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
    if obj.is_instance_of::<PyBool>() || type_name == "bool" || type_name == "bool_" {
        return extract(obj, ParameterError::new_err, what);
    }
    Err(ParameterError::new_err(format!("{what} must be True or False, got {type_name} {}", repr(obj))))
}

fn repr(obj: &Bound<'_, PyAny>) -> String {
    obj.repr().map(|r| r.to_string()).unwrap_or_else(|_| "<unprintable>".into())
}

fn rows3<T: numpy::Element + Copy>(class: ErrorClass, what: &str, a: &PyReadonlyArray2<'_, T>) -> PyResult<Vec<[T; 3]>> {
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(class(format!("{what} must have shape (N, 3), got {shape:?}")));
    }
    Ok(a.as_array().rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

fn vec3(class: ErrorClass, what: &str, a: &PyReadonlyArray1<'_, f32>) -> PyResult<[f32; 3]> {
    let s = a.as_array();
    if s.len() != 3 {
        return Err(class(format!("{what} must have 3 components, got {}", s.len())));
    }
    Ok([s[0], s[1], s[2]])
}

/// `penumbra.scene.CoreScene`: the scene as it crosses the binding.
#[derive(FromPyObject)]
struct CoreScene<'py> {
    meshes: Vec<Bound<'py, PyAny>>,
    light: Bound<'py, PyAny>,
    ambient: PyReadonlyArray1<'py, f32>,
}

/// `penumbra.scene.CoreMesh`: one mesh, its arrays already float32/uint32.
#[derive(FromPyObject)]
struct CoreMesh<'py> {
    name: String,
    vertices: PyReadonlyArray2<'py, f32>,
    faces: PyReadonlyArray2<'py, u32>,
    normals: Option<PyReadonlyArray2<'py, f32>>,
    albedo: PyReadonlyArray1<'py, f32>,
    object_id: i64,
    transform: PyReadonlyArray2<'py, f32>,
}

/// `penumbra.scene.CoreLight`.
#[derive(FromPyObject)]
struct CoreLight<'py> {
    center: PyReadonlyArray1<'py, f32>,
    radius: f32,
    intensity: PyReadonlyArray1<'py, f32>,
}

/// `penumbra.scene.CoreCamera`.
#[derive(FromPyObject)]
struct CoreCamera<'py> {
    eye: PyReadonlyArray1<'py, f32>,
    target: PyReadonlyArray1<'py, f32>,
    up: PyReadonlyArray1<'py, f32>,
    fov_y: f32,
    width: u32,
    height: u32,
}

fn mesh(index: usize, obj: &Bound<'_, PyAny>) -> PyResult<core::Mesh> {
    let m: CoreMesh<'_> = extract(obj, MeshError::new_err, &format!("meshes[{index}]"))?;
    let name = m.name;
    let mesh_error: ErrorClass = MeshError::new_err;
    let t = m.transform.as_array();
    if t.shape() != [4, 4] {
        return Err(mesh_error(format!("mesh '{name}': transform must have shape (4, 4), got {:?}", t.shape())));
    }
    // numpy is row-major; glam takes columns.
    let transform = glam::Mat4::from_cols_array_2d(&std::array::from_fn(|c| std::array::from_fn(|r| t[[r, c]])));
    let object_id = i32::try_from(m.object_id).map_err(|_| {
        to_py(core::Error::InvalidMesh { mesh: name.clone(), message: format!("object_id {} does not fit in int32", m.object_id) })
    })?;
    let what = |field: &str| format!("mesh '{name}': {field}");
    Ok(core::Mesh {
        vertices: rows3(mesh_error, &what("vertices"), &m.vertices)?,
        faces: rows3(mesh_error, &what("faces"), &m.faces)?,
        normals: m.normals.map(|n| rows3(mesh_error, &what("normals"), &n)).transpose()?,
        albedo: vec3(mesh_error, &what("albedo"), &m.albedo)?,
        object_id,
        transform,
        name,
    })
}

fn scene(obj: &Bound<'_, PyAny>) -> PyResult<core::Scene> {
    let s: CoreScene<'_> = extract(obj, SceneError::new_err, "scene")?;
    let light: CoreLight<'_> = extract(&s.light, LightError::new_err, "light")?;
    let light_error: ErrorClass = LightError::new_err;
    Ok(core::Scene {
        meshes: s.meshes.iter().enumerate().map(|(i, m)| mesh(i, m)).collect::<PyResult<_>>()?,
        light: core::SphereLight {
            center: vec3(light_error, "light center", &light.center)?,
            radius: light.radius,
            intensity: vec3(light_error, "light intensity", &light.intensity)?,
        },
        ambient: vec3(SceneError::new_err, "ambient", &s.ambient)?,
    })
}

fn camera(obj: &Bound<'_, PyAny>) -> PyResult<core::Camera> {
    let c: CoreCamera<'_> = extract(obj, CameraError::new_err, "camera")?;
    let camera_error: ErrorClass = CameraError::new_err;
    Ok(core::Camera {
        eye: vec3(camera_error, "camera eye", &c.eye)?,
        target: vec3(camera_error, "camera target", &c.target)?,
        up: vec3(camera_error, "camera up", &c.up)?,
        fov_y_degrees: c.fov_y,
        width: c.width,
        height: c.height,
    })
}

fn param_value(name: &str, v: &Bound<'_, PyAny>) -> PyResult<core::ParamValue> {
    let parameter_error: ErrorClass = ParameterError::new_err;
    let what = format!("parameter '{name}'");
    if v.is_instance_of::<PyBool>() {
        return Ok(core::ParamValue::Bool(extract(v, parameter_error, &what)?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(core::ParamValue::Str(extract(v, parameter_error, &what)?));
    }
    // Python and numpy integers (anything with __index__; floats have none).
    if v.hasattr("__index__")? {
        return match v.extract::<i64>() {
            Ok(i) => Ok(core::ParamValue::Int(i)),
            Err(_) => {
                let value = v.call_method0("__index__").map(|i| repr(&i)).unwrap_or_else(|_| repr(v));
                Err(parameter_error(format!(
                    "parameter '{name}' is the integer {value}, beyond the 64-bit range of integer parameters"
                )))
            }
        };
    }
    if let Ok(f) = v.extract::<f64>() {
        return Ok(core::ParamValue::Float(f));
    }
    Err(to_py(core::Error::InvalidParameter(format!(
        "parameter '{name}' has unsupported type {}; use bool, int, float or str",
        v.get_type().name()?
    ))))
}

fn param_to_py<'py>(py: Python<'py>, v: &core::ParamValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        core::ParamValue::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        core::ParamValue::Int(i) => i.into_pyobject(py)?.into_any(),
        core::ParamValue::Float(f) => f.into_pyobject(py)?.into_any(),
        core::ParamValue::Str(s) => s.into_pyobject(py)?.into_any(),
    })
}

fn summary_dict<'py>(py: Python<'py>, s: &core::AdapterSummary) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &s.name)?;
    d.set_item("backend", &s.backend)?;
    d.set_item("device_type", &s.device_type)?;
    d.set_item("driver", &s.driver)?;
    d.set_item("driver_info", &s.driver_info)?;
    d.set_item("timestamp_queries", s.timestamp_queries)?;
    d.set_item("ray_queries", s.ray_queries)?;
    d.set_item("is_software", s.is_software)?;
    Ok(d)
}

/// Moves an image's pixels into a numpy array without copying them again.
/// A shape that does not match the pixels is a bug of the core, not of the
/// caller's input or the GPU: an `InternalError`.
fn image_to_py<'py>(py: Python<'py>, image: core::Image) -> PyResult<Bound<'py, PyAny>> {
    let shape_err = |e: numpy::ndarray::ShapeError| InternalError::new_err(format!("image '{}': {e}", image.name));
    // Images are 2 (height, width) to 4 (layers, height, width, channels)
    // dimensions: a cube map's colour intermediates have all four.
    let shape = IxDyn(&image.shape);
    if !(2..=4).contains(&image.shape.len()) {
        return Err(InternalError::new_err(format!("image '{}' has unexpected shape {:?}", image.name, image.shape)));
    }
    Ok(match image.data {
        core::ImageData::F32(v) => ArrayD::from_shape_vec(shape, v).map_err(shape_err)?.into_pyarray(py).into_any(),
        core::ImageData::I32(v) => ArrayD::from_shape_vec(shape, v).map_err(shape_err)?.into_pyarray(py).into_any(),
    })
}

/// The long-lived renderer (`penumbra.Renderer` wraps it).
#[pyclass(frozen, module = "penumbra._core")]
struct Renderer {
    inner: core::Renderer,
}

#[pymethods]
impl Renderer {
    #[new]
    #[pyo3(signature = (timing = None, pass_cache = None))]
    fn new(py: Python<'_>, timing: Option<&Bound<'_, PyAny>>, pass_cache: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let mode = match timing {
            None => core::TimingMode::Auto,
            Some(t) => {
                let name: String = t.extract().map_err(|_| {
                    ParameterError::new_err(format!("timing must be 'auto' or 'cpu', got {}", repr(t)))
                })?;
                name.parse::<core::TimingMode>().map_err(to_py)?
            }
        };
        let pass_cache = pass_cache.map(|p| strict_bool(p, "pass_cache")).transpose()?.unwrap_or(true);
        let inner = py.detach(|| core::Renderer::with_pass_cache(mode.uses_timestamps(), pass_cache)).map_err(to_py)?;
        Ok(Self { inner })
    }

    #[getter]
    fn pass_cache(&self) -> bool {
        self.inner.pass_cache_enabled()
    }

    /// Entries the pass cache holds, per pass kind.
    fn pass_cache_entries<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, n) in self.inner.pass_cache_entries() {
            d.set_item(name, n)?;
        }
        Ok(d)
    }

    /// Drops every cached pass output.
    fn clear_pass_cache(&self) {
        self.inner.clear_pass_cache();
    }

    /// What the resource pool holds: counts, and bytes in use and free.
    fn pool_stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.inner.pool_stats();
        let d = PyDict::new(py);
        d.set_item("textures", s.textures)?;
        d.set_item("buffers", s.buffers)?;
        d.set_item("bind_groups", s.bind_groups)?;
        d.set_item("bytes_in_use", s.bytes_in_use)?;
        d.set_item("bytes_free", s.bytes_free)?;
        Ok(d)
    }

    /// Releases every pooled GPU resource not in use.
    fn clear_pool(&self) {
        self.inner.clear_pool();
    }

    fn adapter_info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        summary_dict(py, self.inner.adapter())
    }

    #[getter]
    fn timing_source(&self) -> &'static str {
        if self.inner.uses_timestamps() {
            core::TimingSource::GpuTimestamps.as_str()
        } else {
            core::TimingSource::CpuClock.as_str()
        }
    }

    /// Renders a `CoreScene` seen by a `CoreCamera`; returns a dict of
    /// images, timings and stats.
    #[pyo3(signature = (scene, camera, method, params, intermediates = None, outputs = None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        scene: &Bound<'py, PyAny>,
        camera: &Bound<'py, PyAny>,
        method: &Bound<'py, PyAny>,
        params: &Bound<'py, PyAny>,
        intermediates: Option<&Bound<'py, PyAny>>,
        outputs: Option<Vec<String>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let parameter_error: ErrorClass = ParameterError::new_err;
        let scene = self::scene(scene)?;
        let camera = self::camera(camera)?;
        let method: String = extract(method, parameter_error, "method")?;
        let params = params
            .cast::<PyDict>()
            .map_err(|_| ParameterError::new_err(format!("params must be a dict, got {}", repr(params))))?;
        let mut parsed = BTreeMap::new();
        for (k, v) in params.iter() {
            let key: String = extract(&k, parameter_error, "parameter name")?;
            let value = param_value(&key, &v)?;
            parsed.insert(key, value);
        }
        let config = core::MethodConfig::parse(&method, &parsed).map_err(to_py)?;
        let intermediates = intermediates.map(|i| strict_bool(i, "intermediates")).transpose()?.unwrap_or(false);
        let outputs = match &outputs {
            None => core::Outputs::ALL,
            Some(names) => core::Outputs::parse(names.iter().map(String::as_str)).map_err(to_py)?,
        };
        let options = core::RenderOptions { intermediates, outputs };
        let inner = &self.inner;
        let result = py.detach(|| inner.render(&scene, &camera, &config, &options)).map_err(to_py)?;

        let out = PyDict::new(py);
        out.set_item("method", result.method)?;
        let params = PyDict::new(py);
        for (k, v) in &result.params {
            params.set_item(k, param_to_py(py, v)?)?;
        }
        out.set_item("params", params)?;
        let timings = PyDict::new(py);
        for (name, ms) in &result.timings.passes {
            timings.set_item(name, ms)?;
        }
        out.set_item("timings", timings)?;
        out.set_item("timing_source", result.timings.source.as_str())?;
        out.set_item("total_ms", result.total_ms)?;
        let stats = PyDict::new(py);
        for (k, v) in &result.stats {
            stats.set_item(k, v)?;
        }
        out.set_item("stats", stats)?;
        let images = PyDict::new(py);
        for image in result.images {
            let name = image.name.clone();
            images.set_item(name, image_to_py(py, image)?)?;
        }
        out.set_item("images", images)?;
        Ok(out)
    }
}

/// The adapter a renderer would pick, as a dict.
#[pyfunction]
fn adapter_info(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let summary = py.detach(core::adapter_summary).map_err(to_py)?;
    summary_dict(py, &summary)
}

/// Every registered method name with whether it is implemented (all are).
#[pyfunction]
fn methods(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    PyList::new(py, core::methods())
}

/// Each implemented method's declaration: name, paper and parameters (name,
/// type, default, range or choices, doc), as the core's registry holds it.
#[pyfunction]
fn method_specs(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let out = PyList::empty(py);
    for entry in core::REGISTRY {
        let method = PyDict::new(py);
        method.set_item("name", entry.name)?;
        method.set_item("paper", entry.paper)?;
        let params = PyList::empty(py);
        for spec in (entry.specs)() {
            let p = PyDict::new(py);
            p.set_item("name", spec.name)?;
            p.set_item("default", param_to_py(py, &spec.default)?)?;
            p.set_item("doc", spec.doc)?;
            p.set_item("range", spec.range())?;
            match &spec.kind {
                core::ParamKind::Bool => p.set_item("type", "bool")?,
                core::ParamKind::Int { min, max } => {
                    p.set_item("type", "int")?;
                    p.set_item("minimum", min)?;
                    p.set_item("maximum", max)?;
                }
                core::ParamKind::MapSize { min, max } => {
                    // An integer parameter that also takes "auto".
                    p.set_item("type", "int")?;
                    p.set_item("minimum", min)?;
                    p.set_item("maximum", max)?;
                    p.set_item("choices", vec!["auto"])?;
                }
                core::ParamKind::Float { min, max, min_exclusive } => {
                    p.set_item("type", "float")?;
                    p.set_item("minimum", min)?;
                    p.set_item("maximum", max)?;
                    p.set_item("minimum_exclusive", min_exclusive)?;
                }
                core::ParamKind::Choice(choices) => {
                    p.set_item("type", "choice")?;
                    p.set_item("choices", choices.to_vec())?;
                }
            }
            params.append(p)?;
        }
        method.set_item("params", params)?;
        out.append(method)?;
    }
    Ok(out)
}

/// Writes a linear float32 image, (H, W) or (H, W, 3): `.png` as sRGB 8-bit, `.exr` linear.
#[pyfunction]
fn write_image(py: Python<'_>, path: &Bound<'_, PyAny>, image: &Bound<'_, PyAny>) -> PyResult<()> {
    let parameter_error: ErrorClass = ParameterError::new_err;
    let path: PathBuf = extract(path, parameter_error, "path (a str or os.PathLike)")?;
    let image: PyReadonlyArrayDyn<'_, f32> = extract(image, parameter_error, "image (a float32 numpy array)")?;
    let shape = image.shape().to_vec();
    let (h, w, c) = match shape.as_slice() {
        &[h, w] => (h, w, 1),
        &[h, w, 3] => (h, w, 3),
        other => {
            return Err(to_py(core::Error::InvalidParameter(format!(
                "an image must have shape (H, W) or (H, W, 3), got {other:?}"
            ))))
        }
    };
    let data: Vec<f32> = image.as_array().iter().copied().collect();
    let (h, w) = (u32::try_from(h), u32::try_from(w));
    let (Ok(h), Ok(w)) = (h, w) else {
        return Err(to_py(core::Error::InvalidParameter("image too large".into())));
    };
    py.detach(|| core::image_io::write_image(&path, &data, w, h, c)).map_err(to_py)
}

#[pymodule]
mod _core {
    #[pymodule_export]
    use super::{adapter_info, method_specs, methods, write_image, Renderer};

    #[pymodule_init]
    fn init(m: &pyo3::Bound<'_, pyo3::types::PyModule>) -> pyo3::PyResult<()> {
        use pyo3::types::PyModuleMethods;
        use pyo3::PyTypeInfo;
        let py = m.py();
        m.add("__version__", env!("CARGO_PKG_VERSION"))?;
        // The classes this module raises, so that `_core.pyi` declares them.
        m.add("MeshError", super::MeshError::type_object(py))?;
        m.add("LightError", super::LightError::type_object(py))?;
        m.add("CameraError", super::CameraError::type_object(py))?;
        m.add("SceneError", super::SceneError::type_object(py))?;
        m.add("ParameterError", super::ParameterError::type_object(py))?;
        m.add("GpuUnavailableError", super::GpuUnavailableError::type_object(py))?;
        m.add("GpuError", super::GpuError::type_object(py))?;
        m.add("GpuFeatureError", super::GpuFeatureError::type_object(py))?;
        m.add("PenumbraIOError", super::PenumbraIOError::type_object(py))?;
        m.add("InternalError", super::InternalError::type_object(py))?;
        Ok(())
    }
}
