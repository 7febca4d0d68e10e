//! Small builders for bind-group layout entries and textures, so each pass
//! states *what* it binds rather than repeating wgpu's descriptors.

use wgpu::util::DeviceExt;

pub fn texture(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A float texture read with `textureLoad` only (32-bit floats are unfilterable).
pub fn float_texture(binding: u32) -> wgpu::BindGroupLayoutEntry {
    texture(binding, wgpu::TextureSampleType::Float { filterable: false })
}

pub fn depth_texture(binding: u32) -> wgpu::BindGroupLayoutEntry {
    texture(binding, wgpu::TextureSampleType::Depth)
}

/// A write-only storage image (compute), `texture_storage_2d`.
pub fn storage_texture(binding: u32, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    write_only_storage(binding, format, wgpu::TextureViewDimension::D2)
}

/// The visibility image a screen pass writes (`texture_storage_2d<r32float, write>`).
pub fn visibility_storage(binding: u32) -> wgpu::BindGroupLayoutEntry {
    storage_texture(binding, super::formats::VISIBILITY)
}

/// A write-only storage binding of a light-space array image (compute),
/// `texture_storage_2d_array`.
pub fn storage_array_texture(binding: u32, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    write_only_storage(binding, format, wgpu::TextureViewDimension::D2Array)
}

fn write_only_storage(binding: u32, format: wgpu::TextureFormat, view_dimension: wgpu::TextureViewDimension) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture { access: wgpu::StorageTextureAccess::WriteOnly, format, view_dimension },
        count: None,
    }
}

/// A comparison sampler (`sampler_comparison`), for percentage-closer taps.
pub fn comparison_sampler(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
        count: None,
    }
}

/// A shadow-map comparison sampler passing where the reference depth is at
/// most the stored one; `linear` gives the hardware's 2x2 bilinear PCF
/// (comparison filtering is core WebGPU, so every adapter has it), otherwise
/// the nearest texel decides. Clamped at the map's edges.
pub fn create_comparison_sampler(device: &wgpu::Device, linear: bool) -> wgpu::Sampler {
    let filter = if linear { wgpu::FilterMode::Linear } else { wgpu::FilterMode::Nearest };
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(if linear { "layout::bilinear_comparison" } else { "layout::nearest_comparison" }),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        address_mode_w: wgpu::AddressMode::ClampToEdge,
        mag_filter: filter,
        min_filter: filter,
        compare: Some(wgpu::CompareFunction::LessEqual),
        ..Default::default()
    })
}

pub fn uniform(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The parameter block of a compute pass (`var<storage, read>` in WGSL).
///
/// Compute passes take their per-dispatch parameters from read-only storage
/// buffers, never from uniform buffers. Mesa's lavapipe (22.x, the CI's and
/// many headless machines' Vulkan) "inlines" uniform-buffer values that decide
/// a branch: on every bind it recompiles the shader with the values folded in
/// and, when that removes enough code, keeps doing so for every later dispatch
/// without freeing the old machine code (about 0.16 MiB and an LLVM compile
/// per dispatch; docs/stability.md, "Resident set"). Storage buffers are not
/// inlined. Shaders that read parameters in loops (pcf, pcss, pvmf) copy
/// them into `var<private>` once at the top of `shade`: lavapipe gathers and
/// bounds-checks every storage load and does not hoist them, which made
/// `pcss` 2.2-2.7 times `hard` at 256x256 until the copy, 1.6-1.8 after
/// (`penumbra bench --config benchmarks/builtin.toml`; docs/stability.md).
/// `tests/shader_validation.rs` keeps uniform buffers out of shaders that branch.
pub fn parameters(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry { visibility: wgpu::ShaderStages::COMPUTE, ..storage_buffer(binding) }
}

/// A buffer holding `value` for a [`parameters`] binding.
pub fn parameter_buffer<T: bytemuck::Pod>(device: &wgpu::Device, label: &str, value: &T) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::bytes_of(value),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

pub fn storage_buffer(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A read-write storage buffer for compute shaders (accumulators, counters).
pub fn storage_buffer_rw(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: false },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

pub fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
}

/// Binds `resources` in order as bindings 0, 1, 2, ...
pub fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: &[wgpu::BindingResource<'_>],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = resources
        .iter()
        .enumerate()
        .map(|(i, r)| wgpu::BindGroupEntry { binding: i as u32, resource: r.clone() })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
}

pub fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    })
}

/// A render pipeline over one bind group whose vertex and fragment stages
/// are the entry points `(vs, fs)` of `module`: `buffers` in, `targets` and
/// `depth_stencil` out, one sample, default compilation options.
#[allow(clippy::too_many_arguments)]
pub fn render_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
    (vs, fs): (&str, &str),
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    primitive: wgpu::PrimitiveState,
    depth_stencil: Option<wgpu::DepthStencilState>,
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout(device, label, layout)),
        vertex: wgpu::VertexState { module, entry_point: Some(vs), compilation_options: Default::default(), buffers },
        primitive,
        depth_stencil,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState { module, entry_point: Some(fs), compilation_options: Default::default(), targets }),
        multiview_mask: None,
        cache: None,
    })
}

/// A compute pipeline over one bind group, entry point `main`.
pub fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: String,
    layout: &wgpu::BindGroupLayout,
) -> wgpu::ComputePipeline {
    let module = crate::shaders::module(device, label, source);
    compute_pipeline_entry(device, label, &module, layout, "main")
}

/// A compute pipeline of one entry point of `module`, over one bind group.
pub fn compute_pipeline_entry(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    entry_point: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout(device, label, layout)),
        module,
        entry_point: Some(entry_point),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// Records a compute pass that runs `pipeline` once per pixel of a
/// `width` x `height` image, in 8x8 workgroups, with `timestamp_writes`
/// (a whole pass's, or a part's of a named pass).
pub fn dispatch_per_pixel_writes(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind_group: &wgpu::BindGroup,
    (width, height): (u32, u32),
    timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
}

/// A 2D texture: [`create_array_texture`] of one layer.
pub fn create_texture(device: &wgpu::Device, label: &str, size: (u32, u32), format: wgpu::TextureFormat, usage: wgpu::TextureUsages) -> wgpu::Texture {
    create_array_texture(device, label, size, 1, format, usage)
}

/// A 2D array texture of `layers` layers (shadow maps: 1 for a frustum, 6 for cube faces).
pub fn create_array_texture(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    layers: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A texture binding of an array texture (shadow maps and light-space images).
pub fn array_texture(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture { sample_type, view_dimension: wgpu::TextureViewDimension::D2Array, multisampled: false },
        count: None,
    }
}

/// A shadow map (`texture_depth_2d_array`).
pub fn depth_array(binding: u32) -> wgpu::BindGroupLayoutEntry {
    array_texture(binding, wgpu::TextureSampleType::Depth)
}

/// A light-space float image (`texture_2d_array<f32>`, read with `textureLoad`).
pub fn float_array(binding: u32) -> wgpu::BindGroupLayoutEntry {
    array_texture(binding, wgpu::TextureSampleType::Float { filterable: false })
}

/// Depth test `Less` with writes: the first surface along each ray wins.
pub fn nearest_depth(format: wgpu::TextureFormat) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias: Default::default(),
    })
}

/// As [`nearest_depth`], keeping the farthest fragment (for a map cleared to 0).
pub fn farthest_depth(format: wgpu::TextureFormat) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState { depth_compare: Some(wgpu::CompareFunction::Greater), ..nearest_depth(format)? })
}

pub fn view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}
