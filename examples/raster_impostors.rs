//! A rasterising particle renderer of the kind pgt exists to measure: sphere impostors drawn by a
//! wgpu **render pipeline** (vertex + fragment shaders), written as an outside engine would write
//! it. It knows nothing of pgt's scene files: it reads only
//!
//! * `pgt camera SCENE --json` — the view matrix and the WebGPU projection, the image size and
//!   the background radiance, and
//! * `pgt export SCENE -o particles.csv` — centre, radius, linear colour and extinction σ
//!   (`inf` for Θmax = 1) of every particle,
//!
//! either by running the `pgt` binary (`SCENE -o OUT`) or from files the user made
//! (`--camera cam.json --particles particles.csv -o OUT`).
//!
//! The method is the classic one: each particle is a camera-facing quad that covers its
//! silhouette; the fragment shader casts the pixel's ray (through the pixel centre, as pgt
//! does), intersects it with the sphere, and applies docs/design.md §2's emission model to the chord
//! alone, α = 1 − e^{−σ·chord}, colour C·α (premultiplied); particles are sorted by the depth of
//! their centres and blended back to front over the background (`over`, premultiplied). Where
//! spheres overlap this is not what the reference computes (it integrates the summed σ); that
//! difference, plus the Rgba16Float target, is what `pgt compare` then measures.
//!
//! ```sh
//! cargo build --release
//! cargo run --release --example raster_impostors -- scene.toml -o impostors.exr
//! pgt render scene.toml --model emission -o reference.exr
//! pgt compare reference.exr impostors.exr
//! ```
//!
//! Errors print one line and exit with code 2; no adapter is such an error.

use std::path::{Path, PathBuf};

/// The shader: a billboard per instance, ray–sphere per fragment, premultiplied emission.
pub const SHADER: &str = r#"
struct Frame {
    view_proj: mat4x4<f32>,
    // Camera → world (the inverse of the view matrix): the eye is its translation.
    inv_view: mat4x4<f32>,
    // x, y: P[0][0], P[1][1] of the projection; z, w: image width and height in pixels.
    proj_size: vec4<f32>,
};
@group(0) @binding(0) var<uniform> frame: Frame;

struct VsOut {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) center_radius: vec4<f32>,
    @location(1) @interpolate(flat) color_sigma: vec4<f32>,
};

const CORNERS = array<vec2<f32>, 6>(
    vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
    vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
);

@vertex
fn vs_main(
    @builtin(vertex_index) vertex: u32,
    @location(0) center_radius: vec4<f32>,
    @location(1) color_sigma: vec4<f32>,
) -> VsOut {
    var out: VsOut;
    out.center_radius = center_radius;
    out.color_sigma = color_sigma;
    let corner = CORNERS[vertex];
    let eye = frame.inv_view[3].xyz;
    let c = center_radius.xyz;
    let r = center_radius.w;
    let to_c = c - eye;
    let d = length(to_c);
    // The eye inside or at the sphere: the quad would pass through it; cover the screen.
    var full = d <= r * 1.0001;
    var p = vec4<f32>(0.0);
    if !full {
        // A quad through the centre, facing the eye, whose inscribed circle is the silhouette
        // cone's cross-section there: half side d·tan(asin(r/d)) = r·d/√(d² − r²).
        let axis = to_c / d;
        let helper = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(axis.y) > 0.9);
        let s = normalize(cross(axis, helper));
        let t = cross(s, axis);
        let half_side = r * d / sqrt(d * d - r * r);
        for (var k = 0u; k < 4u; k++) {
            let q = CORNERS[k];
            let w = (frame.view_proj * vec4<f32>(c + (q.x * s + q.y * t) * half_side, 1.0)).w;
            // A corner behind the eye: clipping could cut the silhouette; cover the screen.
            full = full || w <= 0.0;
        }
        p = frame.view_proj * vec4<f32>(c + (corner.x * s + corner.y * t) * half_side, 1.0);
    }
    if full {
        out.position = vec4<f32>(corner, 0.5, 1.0);
    } else {
        // Depth is not used (no depth test: the draw order is the sort); z = w/2 keeps every
        // quad between the near and far planes so none is clipped.
        out.position = vec4<f32>(p.xy, 0.5 * p.w, p.w);
    }
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    // The pixel centre in WebGPU's ndc (framebuffer y down, ndc y up), its view-space ray, then
    // world space: the ray pgt's reference sends through this pixel.
    let ndc = vec2<f32>(2.0 * in.position.x / frame.proj_size.z - 1.0,
                        1.0 - 2.0 * in.position.y / frame.proj_size.w);
    let dir_view = vec3<f32>(ndc.x / frame.proj_size.x, ndc.y / frame.proj_size.y, -1.0);
    let dir = normalize((frame.inv_view * vec4<f32>(dir_view, 0.0)).xyz);
    let eye = frame.inv_view[3].xyz;
    // Ray–sphere through the closest approach (stable for distant spheres).
    let c = in.center_radius.xyz;
    let r = in.center_radius.w;
    let oc = c - eye;
    let tc = dot(oc, dir);
    let perp = oc - tc * dir;
    let h2 = r * r - dot(perp, perp);
    if h2 <= 0.0 {
        discard;
    }
    let h = sqrt(h2);
    let t1 = tc + h;
    if t1 <= 0.0 {
        discard;
    }
    let chord = t1 - max(tc - h, 0.0);
    let sigma = in.color_sigma.w;
    // σ < 0 encodes σ = ∞ (Θmax = 1): WGSL has no infinity literal.
    var alpha = 1.0;
    if sigma >= 0.0 {
        alpha = 1.0 - exp(-sigma * chord);
    }
    return vec4<f32>(in.color_sigma.rgb * alpha, alpha);
}
"#;

/// What the renderer reads from `pgt camera --json`.
#[derive(Debug, Clone)]
pub struct CameraInput {
    pub width: u32,
    pub height: u32,
    /// World → view, column-major.
    pub view: [f64; 16],
    /// WebGPU projection, column-major.
    pub projection: [f64; 16],
    pub background: [f64; 3],
}

/// One particle from `pgt export`: centre, radius, linear colour, σ (∞ allowed).
#[derive(Debug, Clone, Copy)]
pub struct ParticleInput {
    pub center: [f64; 3],
    pub radius: f64,
    pub color: [f64; 3],
    pub sigma: f64,
}

/// A rendered frame: linear RGB, row 0 at the top.
#[derive(Debug, Clone)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
    /// The adapter that drew it.
    pub adapter: String,
}

fn numbers<const N: usize>(v: &serde_json::Value, what: &str) -> Result<[f64; N], String> {
    let a = v
        .as_array()
        .filter(|a| a.len() == N)
        .ok_or_else(|| format!("camera JSON: {what} must be an array of {N} numbers"))?;
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(a) {
        *o = x
            .as_f64()
            .ok_or_else(|| format!("camera JSON: {what} holds a non-number"))?;
    }
    Ok(out)
}

/// Parses `pgt camera --json` output (only the fields an engine needs).
pub fn parse_camera(text: &str) -> Result<CameraInput, String> {
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| format!("camera JSON: {e}"))?;
    let size = |k: &str| {
        v[k].as_u64()
            .filter(|&n| n > 0 && n <= 16384)
            .map(|n| n as u32)
            .ok_or_else(|| format!("camera JSON: {k} must be a positive integer"))
    };
    Ok(CameraInput {
        width: size("width")?,
        height: size("height")?,
        view: numbers(&v["view"]["column_major"], "view.column_major")?,
        projection: numbers(
            &v["projection"]["webgpu"]["matrix"]["column_major"],
            "projection.webgpu.matrix.column_major",
        )?,
        background: numbers(&v["background"], "background")?,
    })
}

/// Parses `pgt export` CSV (header row naming the columns; `inf` allowed for sigma).
pub fn parse_particles(text: &str) -> Result<Vec<ParticleInput>, String> {
    let mut lines = text.lines().enumerate();
    let (_, header) = lines.next().ok_or("particles CSV: empty file")?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let col = |name: &str| {
        names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| format!("particles CSV: no '{name}' column in the header"))
    };
    let idx = [
        col("x")?,
        col("y")?,
        col("z")?,
        col("radius")?,
        col("red")?,
        col("green")?,
        col("blue")?,
        col("sigma")?,
    ];
    let mut out = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        let mut v = [0.0f64; 8];
        for (k, &j) in idx.iter().enumerate() {
            let cell = cells
                .get(j)
                .ok_or_else(|| format!("particles CSV:{}: too few columns", i + 1))?;
            v[k] = cell
                .trim()
                .parse::<f64>()
                .map_err(|_| format!("particles CSV:{}: '{cell}' is not a number", i + 1))?;
        }
        out.push(ParticleInput {
            center: [v[0], v[1], v[2]],
            radius: v[3],
            color: [v[4], v[5], v[6]],
            sigma: v[7],
        });
    }
    Ok(out)
}

fn mul(a: &[f64; 16], b: &[f64; 16]) -> [f64; 16] {
    let mut m = [0.0; 16];
    for col in 0..4 {
        for row in 0..4 {
            m[col * 4 + row] = (0..4).map(|k| a[k * 4 + row] * b[col * 4 + k]).sum();
        }
    }
    m
}

/// The inverse of a rigid view matrix [R | t]: [Rᵀ | −Rᵀt] (column-major).
fn rigid_inverse(v: &[f64; 16]) -> [f64; 16] {
    let r = |row: usize, col: usize| v[col * 4 + row];
    let mut m = [0.0; 16];
    for row in 0..3 {
        for col in 0..3 {
            m[col * 4 + row] = r(col, row);
        }
        m[12 + row] = -(0..3).map(|k| r(k, row) * v[12 + k]).sum::<f64>();
    }
    m[15] = 1.0;
    m
}

/// Instances sorted back to front by view depth of the centre: [cx, cy, cz, r, R, G, B, σ]
/// with σ = ∞ sent as −1.
fn sorted_instances(camera: &CameraInput, particles: &[ParticleInput]) -> Vec<[f32; 8]> {
    let v = &camera.view;
    let depth = |p: &ParticleInput| {
        let c = p.center;
        v[2] * c[0] + v[6] * c[1] + v[10] * c[2] + v[14]
    };
    let mut order: Vec<(f64, [f32; 8])> = particles
        .iter()
        .filter(|p| p.radius > 0.0 && p.sigma != 0.0)
        .map(|p| {
            let sigma = if p.sigma.is_infinite() { -1.0 } else { p.sigma };
            let inst = [
                p.center[0],
                p.center[1],
                p.center[2],
                p.radius,
                p.color[0],
                p.color[1],
                p.color[2],
                sigma,
            ]
            .map(|x| x as f32);
            (depth(p), inst)
        })
        .collect();
    // View space looks down −z: the farthest centre has the most negative z and comes first.
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    order.into_iter().map(|(_, i)| i).collect()
}

struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter: String,
}

fn open_gpu() -> Result<Gpu, String> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
    let adapter = adapters
        .iter()
        .find(|a| a.get_info().device_type != wgpu::DeviceType::Cpu)
        .or(adapters.first())
        .ok_or("no GPU adapter found: install mesa-vulkan-drivers (lavapipe) or a GPU driver")?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("raster_impostors"),
        ..Default::default()
    }))
    .map_err(|e| format!("cannot open a device: {e}"))?;
    Ok(Gpu {
        device,
        queue,
        adapter: adapter.get_info().name,
    })
}

/// The render target format: blendable everywhere, half precision (what engines use).
const TARGET: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

fn pipeline(gpu: &Gpu) -> Result<wgpu::RenderPipeline, String> {
    let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = gpu
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("impostors"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
    let attributes = wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4];
    let pipeline = gpu
        .device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("impostors"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 32,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &attributes,
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: TARGET,
                    blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(format!("impostor pipeline: {e}"));
    }
    Ok(pipeline)
}

/// IEEE half → f32 (the render target's format).
fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let frac = (h & 0x3ff) as f32;
    sign * match exp {
        0 => frac * 2f32.powi(-24),
        31 if frac == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        _ => (1.0 + frac / 1024.0) * 2f32.powi(exp - 15),
    }
}

/// Draws the particles; returns the linear image.
pub fn render(camera: &CameraInput, particles: &[ParticleInput]) -> Result<Frame, String> {
    use wgpu::util::DeviceExt;
    let gpu = open_gpu()?;
    let pipeline = pipeline(&gpu)?;
    let (w, h) = (camera.width, camera.height);
    let view_proj = mul(&camera.projection, &camera.view);
    let mut uniforms: Vec<f32> = view_proj.iter().map(|&x| x as f32).collect();
    uniforms.extend(rigid_inverse(&camera.view).iter().map(|&x| x as f32));
    uniforms.extend([
        camera.projection[0] as f32,
        camera.projection[5] as f32,
        w as f32,
        h as f32,
    ]);
    let device = &gpu.device;
    let uniform_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("frame"),
        contents: bytemuck::cast_slice(&uniforms),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let instances = sorted_instances(camera, particles);
    let instance_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("particles"),
        contents: bytemuck::cast_slice(if instances.is_empty() {
            &[[0.0f32; 8]][..]
        } else {
            &instances
        }),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("frame"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: uniform_buffer.as_entire_binding(),
        }],
    });
    let extent = wgpu::Extent3d {
        width: w,
        height: h,
        depth_or_array_layers: 1,
    };
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("target"),
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: TARGET,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = target.create_view(&wgpu::TextureViewDescriptor::default());
    let row_bytes = 8 * w;
    let padded_row =
        row_bytes.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: padded_row as u64 * h as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let bg = camera.background;
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("impostors"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: bg[0],
                        g: bg[1],
                        b: bg[2],
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_vertex_buffer(0, instance_buffer.slice(..));
        pass.draw(0..6, 0..instances.len() as u32);
    }
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: &target,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(h),
            },
        },
        extent,
    );
    gpu.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    readback.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| format!("waiting for the GPU: {e}"))?;
    rx.recv()
        .map_err(|_| "the GPU never answered the read-back".to_string())?
        .map_err(|e| format!("reading the image back: {e}"))?;
    let data = readback
        .get_mapped_range(..)
        .map_err(|e| format!("reading the image back: {e:?}"))?
        .to_vec();
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h as usize {
        let row = &data[y * padded_row as usize..][..row_bytes as usize];
        for px in row.chunks(8) {
            let c = |k: usize| half_to_f32(u16::from_le_bytes([px[2 * k], px[2 * k + 1]]));
            pixels.push([c(0), c(1), c(2)]);
        }
    }
    Ok(Frame {
        width: w,
        height: h,
        pixels,
        adapter: gpu.adapter,
    })
}

/// Linear → 8-bit sRGB (IEC 61966-2-1), clamped.
fn srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Writes `.exr` (linear float R, G, B) or `.png` (8-bit sRGB).
pub fn write(frame: &Frame, path: &Path) -> Result<(), String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let (w, h) = (frame.width as usize, frame.height as usize);
    match ext.as_deref() {
        Some("exr") => exr::prelude::write_rgb_file(path, w, h, |x, y| {
            let p = frame.pixels[y * w + x];
            (p[0], p[1], p[2])
        })
        .map_err(|e| format!("{}: {e}", path.display())),
        Some("png") => {
            let bytes: Vec<u8> = frame.pixels.iter().flat_map(|p| p.map(srgb8)).collect();
            image::save_buffer(
                path,
                &bytes,
                frame.width,
                frame.height,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| format!("{}: {e}", path.display()))
        }
        _ => Err(format!("{}: use a .exr or .png extension", path.display())),
    }
}

/// Runs `pgt ARGS…` and returns its stdout.
pub fn run_pgt(pgt: &Path, args: &[&std::ffi::OsStr]) -> Result<String, String> {
    let out = std::process::Command::new(pgt)
        .args(args)
        .output()
        .map_err(|e| {
            format!(
                "cannot run {}: {e} (build it with `cargo build --release` or pass --pgt PATH)",
                pgt.display()
            )
        })?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).trim().to_string());
    }
    String::from_utf8(out.stdout).map_err(|e| format!("pgt printed non-UTF-8: {e}"))
}

/// The `pgt` binary beside this example's (target/<profile>/pgt), else `pgt` on the PATH.
fn default_pgt() -> PathBuf {
    std::env::current_exe()
        .ok()
        .and_then(|exe| Some(exe.parent()?.parent()?.join("pgt")))
        .filter(|p| p.exists())
        .unwrap_or_else(|| PathBuf::from("pgt"))
}

struct Args {
    scene: Option<PathBuf>,
    camera: Option<PathBuf>,
    particles: Option<PathBuf>,
    output: PathBuf,
    pgt: PathBuf,
}

const USAGE: &str = "usage: raster_impostors SCENE -o OUT.exr|.png [--pgt PATH]\n       \
raster_impostors --camera CAMERA.json --particles PARTICLES.csv -o OUT.exr|.png";

fn parse_args() -> Result<Args, String> {
    let mut it = std::env::args_os().skip(1);
    let (mut scene, mut camera, mut particles, mut output, mut pgt) =
        (None, None, None, None, None);
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .map(PathBuf::from)
                .ok_or(format!("{name} needs a value\n{USAGE}"))
        };
        match a.to_str() {
            Some("-o" | "--output") => output = Some(value("-o")?),
            Some("--camera") => camera = Some(value("--camera")?),
            Some("--particles") => particles = Some(value("--particles")?),
            Some("--pgt") => pgt = Some(value("--pgt")?),
            Some("-h" | "--help") => return Err(USAGE.to_string()),
            _ if scene.is_none() => scene = Some(PathBuf::from(a)),
            _ => return Err(format!("unexpected argument {a:?}\n{USAGE}")),
        }
    }
    let output = output.ok_or(format!("-o OUT is required\n{USAGE}"))?;
    if scene.is_none() && (camera.is_none() || particles.is_none()) {
        return Err(USAGE.to_string());
    }
    Ok(Args {
        scene,
        camera,
        particles,
        output,
        pgt: pgt.unwrap_or_else(default_pgt),
    })
}

fn read(path: &Path) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

fn main_inner() -> Result<(), String> {
    let args = parse_args()?;
    let tmp = std::env::temp_dir().join(format!("raster_impostors_{}.csv", std::process::id()));
    let (camera_text, particles_text) = match (&args.camera, &args.particles, &args.scene) {
        (Some(c), Some(p), _) => (read(c)?, read(p)?),
        (_, _, Some(scene)) => {
            let camera = run_pgt(
                &args.pgt,
                &["camera".as_ref(), scene.as_os_str(), "--json".as_ref()],
            )?;
            run_pgt(
                &args.pgt,
                &[
                    "export".as_ref(),
                    scene.as_os_str(),
                    "-o".as_ref(),
                    tmp.as_os_str(),
                ],
            )?;
            let particles = read(&tmp);
            let _ = std::fs::remove_file(&tmp);
            (camera, particles?)
        }
        _ => return Err(USAGE.to_string()),
    };
    let camera = parse_camera(&camera_text)?;
    let particles = parse_particles(&particles_text)?;
    let t = std::time::Instant::now();
    let frame = render(&camera, &particles)?;
    write(&frame, &args.output)?;
    eprintln!(
        "raster_impostors: {} particles, {}x{}, {:.3} s on {}, wrote {}",
        particles.len(),
        frame.width,
        frame.height,
        t.elapsed().as_secs_f64(),
        frame.adapter,
        args.output.display()
    );
    Ok(())
}

#[allow(dead_code)]
fn main() -> std::process::ExitCode {
    match main_inner() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
