//! Typed errors of the core. The binding crate maps each variant to its own
//! Python exception class (`python/penumbra/errors.py`).

/// Everything that can go wrong in the core, by cause.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// A mesh is malformed: non-finite coordinates, indices out of range, empty or degenerate.
    #[error("mesh '{mesh}': {message}")]
    InvalidMesh { mesh: String, message: String },
    /// The light is malformed (negative or non-finite radius, ...).
    #[error("light: {0}")]
    InvalidLight(String),
    /// The camera is malformed (zero-size image, degenerate look-at, ...).
    #[error("camera: {0}")]
    InvalidCamera(String),
    /// The scene as a whole cannot be rendered (no meshes, light inside geometry, ...).
    #[error("scene: {0}")]
    InvalidScene(String),
    /// Unknown method, unknown parameter, wrong type or out-of-range value.
    #[error("{0}")]
    InvalidParameter(String),
    /// No adapter could be found or a device could not be created.
    #[error("{0}")]
    GpuUnavailable(String),
    /// The adapter lacks a feature a method needs (ray queries for `raytraced`);
    /// the message names the feature, the adapter and how to get one that has it.
    #[error("{0}")]
    MissingFeature(String),
    /// The GPU reported an error while rendering (validation, device lost).
    #[error("GPU error: {0}")]
    Gpu(String),
    /// The GPU ran out of memory. The renderer rewrites the adapter's words
    /// into a message naming what the render asked for (image size, map size
    /// and projection) and what to lower (`Renderer::render`).
    #[error("{0}")]
    OutOfMemory(String),
    /// Reading or writing a file failed.
    #[error("{0}")]
    Io(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn mesh(mesh: &str, message: impl Into<String>) -> Self {
        Self::InvalidMesh {
            mesh: mesh.to_owned(),
            message: message.into(),
        }
    }
}
