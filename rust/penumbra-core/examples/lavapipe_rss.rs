//! Minimal resident-set experiment behind docs/stability.md ("Resident set"):
//! one compute dispatch per iteration that reads a 256x256 texture, with a
//! fresh view, uniform buffer and bind group each time (as a render does),
//! submitted and waited for. Prints the resident-set growth per dispatch.
//!
//! `cargo run --example lavapipe_rss -- VARIANT N`, VARIANT one of
//! - `depth_load`: `texture_depth_2d` read with `textureLoad`, no sampler in the layout (as `hard` did)
//! - `depth_load_sampler`: the same plus a non-filtering sampler used by `textureSampleLevel` once
//! - `depth_sample`: `texture_depth_2d` read with `textureSampleLevel` and a nearest sampler
//! - `float_load`: an `r32float` texture read with `textureLoad`, no sampler
//! - `depth_load_reused`: `depth_load` with one bind group made once and reused

use wgpu::util::DeviceExt;

fn rss_mib() -> f64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap();
    let pages: f64 = statm.split_whitespace().nth(1).unwrap().parse().unwrap();
    pages * 4096.0 / (1024.0 * 1024.0)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let variant = args.get(1).map(String::as_str).unwrap_or("depth_load").to_owned();
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(200);
    // A trailing `_fresh`: a new texture each dispatch (as each render makes its shadow map).
    let fresh_texture = variant.ends_with("_fresh");
    let variant = variant.trim_end_matches("_fresh").to_owned();
    // `hard_like`/`hard_like_sampler`: `depth_load`/`depth_load_sampler` plus two
    // r32float textures read with textureLoad, as `hard` reads the G-buffer.
    let extra = variant.starts_with("hard_like");
    let variant = if extra { variant.replace("hard_like", "depth_load") } else { variant };
    let depth = variant.starts_with("depth");
    let sampler = matches!(variant.as_str(), "depth_load_sampler" | "depth_sample");
    let (tex_decl, read) = match variant.as_str() {
        "depth_load" | "depth_load_reused" => ("texture_depth_2d", "textureLoad(map, p, 0)"),
        "depth_load_sampler" => (
            "texture_depth_2d",
            "textureLoad(map, p, 0) + select(0.0, textureSampleLevel(map, smp, vec2<f32>(0.5), 0), u.x > 1e30)",
        ),
        "depth_sample" => ("texture_depth_2d", "textureSampleLevel(map, smp, (vec2<f32>(p) + 0.5) / 256.0, 0)"),
        "float_load" => ("texture_2d<f32>", "textureLoad(map, p, 0).x"),
        other => panic!("unknown variant {other}"),
    };
    let source = format!(
        "@group(0) @binding(0) var map: {tex_decl};\n\
         @group(0) @binding(1) var<uniform> u: vec4<f32>;\n\
         @group(0) @binding(2) var<storage, read_write> out: array<f32>;\n\
         {}\n{}\n\
         @compute @workgroup_size(8, 8)\n\
         fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             let p = vec2<i32>(id.xy);\n\
             out[id.y * 256u + id.x] = {read} * u.y{};\n\
         }}\n",
        if sampler { "@group(0) @binding(3) var smp: sampler;" } else { "" },
        if extra { "@group(0) @binding(4) var g0: texture_2d<f32>; @group(0) @binding(5) var g1: texture_2d<f32>;" } else { "" },
        if extra { " + textureLoad(g0, p, 0).x + textureLoad(g1, p, 0).x" } else { "" },
    );
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).expect("adapter");
    let (device, queue) = pollster::block_on(adapter.request_device(&Default::default())).expect("device");
    let format = if depth { wgpu::TextureFormat::Depth32Float } else { wgpu::TextureFormat::R32Float };
    let new_texture = || device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: 256, height: 256, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let texture = new_texture();
    let mut entries = vec![
        wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: if depth { wgpu::TextureSampleType::Depth } else { wgpu::TextureSampleType::Float { filterable: false } },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        },
        wgpu::BindGroupLayoutEntry {
            binding: 1,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        },
        wgpu::BindGroupLayoutEntry {
            binding: 2,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: false }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        },
    ];
    if sampler {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 3,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
            count: None,
        });
    }
    if !sampler && extra {
        // Keep the bindings contiguous in the layout: a dummy slot 3 is not needed, wgpu allows gaps.
    }
    if extra {
        for binding in [4, 5] {
            entries.push(wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            });
        }
    }
    let float_texture = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: 256, height: 256, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let float_view = float_texture.create_view(&Default::default());
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &entries });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor { label: None, source: wgpu::ShaderSource::Wgsl(source.into()) });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let smp = device.create_sampler(&wgpu::SamplerDescriptor::default());
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 256 * 256 * 4,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let make = |texture: &wgpu::Texture| {
        let view = texture.create_view(&Default::default());
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(&[0.0f32, 1.0, 0.0, 0.0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let mut resources = vec![
            wgpu::BindingResource::TextureView(&view),
            uniforms.as_entire_binding(),
            out.as_entire_binding(),
        ];
        if sampler {
            resources.push(wgpu::BindingResource::Sampler(&smp));
        }
        let mut entries: Vec<_> = resources
            .into_iter()
            .enumerate()
            .map(|(i, resource)| wgpu::BindGroupEntry { binding: i as u32, resource })
            .collect();
        if extra {
            for binding in [4, 5] {
                entries.push(wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(&float_view) });
            }
        }
        device.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout: &layout, entries: &entries })
    };
    let reused = make(&texture);
    let step = |i: usize| {
        let fresh;
        let group = if variant == "depth_load_reused" {
            &reused
        } else {
            fresh = make(&if fresh_texture { new_texture() } else { texture.clone() });
            &fresh
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(32, 32, 1);
        }
        queue.submit([encoder.finish()]);
        device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
        i
    };
    for i in 0..20 {
        step(i);
    }
    let start = rss_mib();
    for i in 0..n {
        step(i);
    }
    let end = rss_mib();
    println!("{variant}: {start:.1} -> {end:.1} MiB over {n} dispatches, {:.4} MiB per dispatch", (end - start) / n as f64);
}
