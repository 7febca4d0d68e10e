//! pyo3 bindings of penumbra-core, and nothing else: conversions between
//! numpy/Python values and core types, error mapping, and releasing the GIL
//! around rendering and readback. The Python API proper is `python/penumbra`.

use std::collections::BTreeMap;

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use penumbra_core as core;
use pyo3::exceptions::PyTypeError;
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
pyo3::import_exception!(penumbra.errors, PenumbraIOError);

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
        core::Error::Gpu(_) => GpuError::new_err(message),
        core::Error::Io(_) => PenumbraIOError::new_err(message),
    }
}

fn rows3<T: numpy::Element + Copy>(what: &str, a: &PyReadonlyArray2<'_, T>) -> PyResult<Vec<[T; 3]>> {
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(PyTypeError::new_err(format!("{what} must have shape (N, 3), got {shape:?}")));
    }
    let array = a.as_array();
    Ok(array.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

fn vec3(what: &str, a: PyReadonlyArray1<'_, f32>) -> PyResult<[f32; 3]> {
    let s = a.as_array();
    if s.len() != 3 {
        return Err(PyTypeError::new_err(format!("{what} must have 3 components, got {}", s.len())));
    }
    Ok([s[0], s[1], s[2]])
}

/// One mesh as `penumbra.scene.Mesh._core_args()` packs it.
type MeshArgs<'py> = (
    String,
    PyReadonlyArray2<'py, f32>,
    PyReadonlyArray2<'py, u32>,
    Option<PyReadonlyArray2<'py, f32>>,
    PyReadonlyArray1<'py, f32>,
    i64,
    PyReadonlyArray2<'py, f32>,
);

fn mesh(args: MeshArgs<'_>) -> PyResult<core::Mesh> {
    let (name, vertices, faces, normals, albedo, object_id, transform) = args;
    let t = transform.as_array();
    if t.shape() != [4, 4] {
        return Err(PyTypeError::new_err(format!("transform must have shape (4, 4), got {:?}", t.shape())));
    }
    // numpy is row-major; glam takes columns.
    let transform = glam::Mat4::from_cols_array_2d(&std::array::from_fn(|c| std::array::from_fn(|r| t[[r, c]])));
    let object_id = i32::try_from(object_id).map_err(|_| {
        to_py(core::Error::InvalidMesh { mesh: name.clone(), message: format!("object_id {object_id} does not fit in int32") })
    })?;
    Ok(core::Mesh {
        vertices: rows3("vertices", &vertices)?,
        faces: rows3("faces", &faces)?,
        normals: normals.map(|n| rows3("normals", &n)).transpose()?,
        albedo: vec3("albedo", albedo)?,
        object_id,
        transform,
        name,
    })
}

fn param_value(name: &str, v: &Bound<'_, PyAny>) -> PyResult<core::ParamValue> {
    if v.is_instance_of::<PyBool>() {
        return Ok(core::ParamValue::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(core::ParamValue::Str(v.extract()?));
    }
    if let Ok(i) = v.extract::<i64>() {
        return Ok(core::ParamValue::Int(i));
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
    d.set_item("is_software", s.is_software)?;
    Ok(d)
}

/// Moves an image's pixels into a numpy array without copying them again.
fn image_to_py<'py>(py: Python<'py>, image: core::Image) -> PyResult<Bound<'py, PyAny>> {
    let shape_err = |e: numpy::ndarray::ShapeError| GpuError::new_err(format!("image '{}': {e}", image.name));
    Ok(match (image.shape.as_slice(), image.data) {
        (&[h, w], core::ImageData::F32(v)) => Array2::from_shape_vec((h, w), v).map_err(shape_err)?.into_pyarray(py).into_any(),
        (&[h, w], core::ImageData::I32(v)) => Array2::from_shape_vec((h, w), v).map_err(shape_err)?.into_pyarray(py).into_any(),
        (&[h, w, c], core::ImageData::F32(v)) => Array3::from_shape_vec((h, w, c), v).map_err(shape_err)?.into_pyarray(py).into_any(),
        (shape, _) => return Err(GpuError::new_err(format!("image '{}' has unexpected shape {shape:?}", image.name))),
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
    #[pyo3(signature = (timing = "auto", pass_cache = true))]
    fn new(py: Python<'_>, timing: &str, pass_cache: bool) -> PyResult<Self> {
        let use_timestamps = match timing {
            "auto" => true,
            "cpu" => false,
            other => {
                return Err(to_py(core::Error::InvalidParameter(format!(
                    "timing must be 'auto' or 'cpu', got {other:?}"
                ))))
            }
        };
        let inner = py.detach(|| core::Renderer::with_pass_cache(use_timestamps, pass_cache)).map_err(to_py)?;
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

    /// Renders and returns a dict of images, timings and stats.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (meshes, light, camera, ambient, method, params, intermediates = false))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        meshes: Vec<MeshArgs<'py>>,
        light: (PyReadonlyArray1<'py, f32>, f32, PyReadonlyArray1<'py, f32>),
        camera: (PyReadonlyArray1<'py, f32>, PyReadonlyArray1<'py, f32>, PyReadonlyArray1<'py, f32>, f32, u32, u32),
        ambient: PyReadonlyArray1<'py, f32>,
        method: &str,
        params: &Bound<'py, PyDict>,
        intermediates: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let scene = core::Scene {
            meshes: meshes.into_iter().map(mesh).collect::<PyResult<_>>()?,
            light: core::SphereLight { center: vec3("light center", light.0)?, radius: light.1, intensity: vec3("light intensity", light.2)? },
            ambient: vec3("ambient", ambient)?,
        };
        let camera = core::Camera {
            eye: vec3("eye", camera.0)?,
            target: vec3("target", camera.1)?,
            up: vec3("up", camera.2)?,
            fov_y_degrees: camera.3,
            width: camera.4,
            height: camera.5,
        };
        let mut parsed = BTreeMap::new();
        for (k, v) in params.iter() {
            let key: String = k.extract()?;
            let value = param_value(&key, &v)?;
            parsed.insert(key, value);
        }
        let config = core::MethodConfig::parse(method, &parsed).map_err(to_py)?;
        let options = core::RenderOptions { intermediates };
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

/// Every method name of SPEC section 4 with whether it is implemented.
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
fn write_image(py: Python<'_>, path: std::path::PathBuf, image: numpy::PyReadonlyArrayDyn<'_, f32>) -> PyResult<()> {
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
        m.add("PenumbraIOError", super::PenumbraIOError::type_object(py))?;
        Ok(())
    }
}
