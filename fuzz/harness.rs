//! What each fuzz target does with its input, and the properties it checks.
//!
//! Shared by the cargo-fuzz targets (`fuzz/fuzz_targets/*.rs`) and by the regression test that
//! replays `tests/fuzz-regressions/<target>/*` in the normal `cargo test`
//! (`tests/suite/fuzz_regressions.rs` includes this file with `#[path]`), so a saved input runs
//! through exactly the code that found it. Each function panics when a property fails; an input
//! the loaders reject with a diagnostic is a pass.
//!
//! Inputs go through the library's in-memory entry points (`load_scene_from_str`,
//! `load_obj_from_bytes`, `load_gltf_from_bytes`), which are the real loaders with the first
//! file already read. Files an input refers to (an MTL file, a buffer, an include) live in one
//! scratch folder per process, and every load is sandboxed to it (`FileAccess::sandboxed`), so
//! an input naming `/dev/zero` or `../../etc/passwd` is refused like any untrusted scene.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use lampshade::diag::render_diagnostics;
use lampshade::mesh::{LoadedMesh, MeshError, MeshOptions, gltf, obj};
use lampshade::render::{DebugView, RenderOptions, render};
use lampshade::scene::access::FileAccess;
use lampshade::scene::load::{LoadOptions, load_scene_from_str};

/// A memory budget small enough that no accepted input takes long to load or render.
const FUZZ_MEMORY_BUDGET: u64 = 256 << 20;

/// The scratch folder, with the files the seeds refer to: `lampshade-fuzz/<pid>` in the
/// temporary folder. A fuzzer ends by aborting, and a static is never dropped, so nothing
/// removes it at exit; instead each process removes the folders of processes that are gone
/// (on Linux, where `/proc` says which are).
fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let parent = std::env::temp_dir().join("lampshade-fuzz");
        if Path::new("/proc/self").exists() {
            for entry in std::fs::read_dir(&parent).into_iter().flatten().flatten() {
                let name = entry.file_name();
                let gone = name
                    .to_str()
                    .and_then(|pid| pid.parse::<u32>().ok())
                    .is_some_and(|pid| !Path::new("/proc").join(pid.to_string()).exists());
                if gone {
                    let _ = std::fs::remove_dir_all(entry.path());
                }
            }
        }
        let dir = parent.join(std::process::id().to_string());
        std::fs::create_dir_all(&dir).expect("a scratch folder");
        let dir = std::fs::canonicalize(dir).expect("the scratch folder exists");
        std::fs::write(
            dir.join("lib.ron"),
            "Materials(materials: { \"gold\": (color: (1, 0.8, 0.2), shininess: 40) })",
        )
        .unwrap();
        std::fs::write(
            dir.join("tri.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1/1 2/2/1 3/3/1\n",
        )
        .unwrap();
        // 3 float positions of one triangle followed by 3 u16 indices: the seeds' buffer.
        let mut buffer = Vec::new();
        for value in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            buffer.extend_from_slice(&value.to_le_bytes());
        }
        for index in [0u16, 1, 2] {
            buffer.extend_from_slice(&index.to_le_bytes());
        }
        std::fs::write(dir.join("buffer.bin"), buffer).unwrap();
        dir
    })
}

fn access() -> FileAccess {
    FileAccess::sandboxed(scratch()).expect("the scratch folder is a folder")
}

fn load_options() -> LoadOptions {
    LoadOptions {
        max_memory: Some(FUZZ_MEMORY_BUDGET),
        access: access(),
        ..LoadOptions::default()
    }
}

fn mesh_options() -> MeshOptions {
    MeshOptions {
        access: access(),
        ..MeshOptions::default()
    }
}

/// A mesh that loaded satisfies the mesh invariant; one that did not names its file.
fn check_mesh(result: Result<LoadedMesh, MeshError>, path: &Path) {
    match result {
        Ok(loaded) => {
            if let Err(problem) = loaded.mesh.check_invariant() {
                panic!("a loaded mesh breaks the mesh invariant: {problem}");
            }
        }
        Err(error) => {
            assert!(!error.message.is_empty(), "an empty error message");
            assert!(
                error.path.starts_with(scratch()) || error.path == path,
                "the error names a file outside the scratch folder: {}",
                error.path.display()
            );
        }
    }
}

/// Target `scene`: any text as a scene file. Loading either succeeds with a scene the
/// renderer accepts (image within the limits, every mesh satisfying its invariant) or fails
/// with diagnostics that render (snippets of arbitrary text must not panic).
pub fn scene(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = scratch().join("scene.ron");
    match load_scene_from_str(&path, text, &load_options()) {
        Ok(loaded) => {
            let image = loaded.scene.image;
            assert!(image.width >= 1 && image.width <= lampshade::render::MAX_IMAGE_DIMENSION);
            assert!(image.height >= 1 && image.height <= lampshade::render::MAX_IMAGE_DIMENSION);
            for object in &loaded.scene.objects {
                if let Err(problem) = object.mesh.check_invariant() {
                    panic!("a loaded mesh breaks the mesh invariant: {problem}");
                }
            }
            render_diagnostics(&loaded.warnings, &loaded.sources, false);
        }
        Err(error) => {
            assert!(
                !error.diagnostics.is_empty(),
                "a failed load without a diagnostic"
            );
            assert!(error.diagnostics.iter().any(|d| d.is_error()));
            let text = render_diagnostics(&error.diagnostics, &error.sources, false);
            assert!(text.contains("error"), "{text}");
        }
    }
}

/// Splits an input in two at the first `separator` (the second part may be absent).
fn split<'a>(data: &'a [u8], separator: &[u8]) -> (&'a [u8], Option<&'a [u8]>) {
    match data.windows(separator.len()).position(|w| w == separator) {
        Some(at) => (&data[..at], Some(&data[at + separator.len()..])),
        None => (data, None),
    }
}

/// Target `obj`: an OBJ file, and after a line `#mtl` the MTL file `m.mtl` beside it.
pub fn obj(data: &[u8]) {
    let (obj_bytes, mtl_bytes) = split(data, b"\n#mtl\n");
    let dir = scratch();
    let _ = std::fs::write(dir.join("m.mtl"), mtl_bytes.unwrap_or_default());
    let path = dir.join("mesh.obj");
    check_mesh(obj::load_obj_from_bytes(&path, obj_bytes, &mesh_options()), &path);
}

/// Target `gltf`: a `.gltf` JSON or `.glb` file (the parser tells them apart by their first
/// bytes); `buffer.bin` beside it holds one triangle.
pub fn gltf(data: &[u8]) {
    let path = scratch().join("mesh.gltf");
    check_mesh(gltf::load_gltf_from_bytes(&path, data, &mesh_options()), &path);
}

/// Reads numbers out of the fuzzer's bytes; zeros once they run out.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn byte(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&first, rest)) => {
                self.0 = rest;
                first
            }
            None => 0,
        }
    }

    fn below(&mut self, n: u8) -> u8 {
        self.byte() % n
    }

    /// A coordinate: mostly ordinary, sometimes extreme (up to ±3·10³⁸, the edge of `f32`).
    fn coordinate(&mut self) -> f64 {
        let mantissa = f64::from(self.byte() as i8) / 16.0;
        match self.below(8) {
            0 => mantissa * 1e30 * 3e8,
            1 => mantissa * 1e-30,
            2 => mantissa * 1e6,
            _ => mantissa,
        }
    }

    fn unit(&mut self) -> f64 {
        f64::from(self.byte()) / 255.0
    }

    /// A non-negative number, sometimes huge.
    fn amount(&mut self) -> f64 {
        let base = self.unit() * 4.0;
        if self.below(8) == 0 { base * 1e30 } else { base }
    }
}

/// Target `render`: a small random scene (random triangles with extreme coordinates, random
/// lights, materials, camera, samples and debug view) written as an OBJ file and a scene,
/// loaded by the real loader and, when it loads, rendered: every pixel must be finite and not
/// negative, and the PNG encoding must succeed.
pub fn render_scene(data: &[u8]) {
    let mut bytes = Bytes(data);
    let dir = scratch();

    let mut obj_text = String::new();
    let vertex_count = 3 + usize::from(bytes.below(10));
    for _ in 0..vertex_count {
        let (x, y, z) = (bytes.coordinate(), bytes.coordinate(), bytes.coordinate());
        obj_text.push_str(&format!("v {x:e} {y:e} {z:e}\n"));
    }
    for _ in 0..1 + bytes.below(12) {
        let mut corner = || 1 + usize::from(bytes.byte()) % vertex_count;
        obj_text.push_str(&format!("f {} {} {}\n", corner(), corner(), corner()));
    }
    let mesh_file = dir.join("render.obj");
    std::fs::write(&mesh_file, obj_text).expect("the scratch folder is writable");

    let models = ["Phong", "BlinnPhong", "Lambert", "Unlit", "CookTorrance"];
    let shadings = ["Constant", "Flat", "Gouraud", "Phong"];
    let back_faces = ["ReverseLit", "Lit", "Unlit", "Cull"];
    let mut objects = String::new();
    for _ in 0..1 + bytes.below(3) {
        let mesh = match bytes.below(4) {
            0 => format!("Sphere(segments: {})", 3 + bytes.below(12)),
            1 => "Cube".to_string(),
            _ => "Obj(\"render.obj\")".to_string(),
        };
        objects.push_str(&format!(
            "(mesh: {mesh}, translate: ({:e}, {:e}, {:e}), scale: {:e}, rotate: ({}, {}, {}),
              shading: {}, back_faces: {},
              material: (color: ({}, {}, {}), ka: {:e}, kd: {:e}, ks: {:e}, shininess: {:e},
                         model: {}, roughness: {}, metallic: {}, distribution: {})),\n",
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.byte(),
            bytes.byte(),
            bytes.byte(),
            shadings[usize::from(bytes.below(4))],
            back_faces[usize::from(bytes.below(4))],
            bytes.unit(),
            bytes.unit(),
            bytes.unit(),
            bytes.amount(),
            bytes.amount(),
            bytes.amount(),
            bytes.amount(),
            models[usize::from(bytes.below(5))],
            0.001 + bytes.unit() * 0.999,
            bytes.unit(),
            if bytes.below(2) == 0 { "Beckmann" } else { "Ggx" },
        ));
    }
    let mut lights = String::new();
    for _ in 0..bytes.below(4) {
        let shadows = if bytes.below(3) == 0 {
            format!(
                "shadows: true, shadow_map: (resolution: {}, filter: {}),",
                16 + bytes.below(48),
                bytes.below(3)
            )
        } else {
            String::new()
        };
        let common = format!(
            "color: ({}, {}, {}), intensity: {:e}, {shadows}",
            bytes.unit(),
            bytes.unit(),
            bytes.unit(),
            bytes.amount()
        );
        let (x, y, z) = (bytes.coordinate(), bytes.coordinate(), bytes.coordinate());
        let (dx, dy, dz) = (bytes.coordinate(), bytes.coordinate(), bytes.coordinate());
        lights.push_str(&match bytes.below(3) {
            0 => format!("Directional(direction: ({dx:e}, {dy:e}, {dz:e}), {common}),\n"),
            1 => format!(
                "Point(position: ({x:e}, {y:e}, {z:e}), attenuation: (constant: 1, linear: {:e}, quadratic: {:e}), {common}),\n",
                bytes.amount(),
                bytes.amount()
            ),
            _ => format!(
                "Spot(position: ({x:e}, {y:e}, {z:e}), direction: ({dx:e}, {dy:e}, {dz:e}), cutoff: {}, exponent: {}, {common}),\n",
                bytes.byte() % 91,
                bytes.byte()
            ),
        });
    }
    let camera = match bytes.below(3) {
        0 => String::new(),
        1 => format!(
            "camera: Perspective(eye: ({:e}, {:e}, {:e}), target: ({:e}, {:e}, {:e}), fov: {}),",
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.coordinate(),
            1 + bytes.below(178)
        ),
        _ => format!(
            "camera: Orthographic(eye: ({:e}, {:e}, {:e}), target: (0, 0, 0), height: {:e}),",
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.coordinate(),
            bytes.amount()
        ),
    };
    let samples = [1, 2, 4, 8, 16][usize::from(bytes.below(5))];
    let scene = format!(
        "Scene(image: (width: {}, height: {}, samples: {samples}), ambient: ({}, {}, {}), {camera}
         lights: [{lights}], objects: [{objects}])",
        1 + bytes.below(40),
        1 + bytes.below(40),
        bytes.unit(),
        bytes.unit(),
        bytes.unit(),
    );
    let debug_view = match bytes.below(8) {
        0 => Some(DebugView::Ambient),
        1 => Some(DebugView::Diffuse),
        2 => Some(DebugView::Specular),
        3 => Some(DebugView::Normals),
        4 => Some(DebugView::Depth),
        _ => None,
    };

    let Ok(loaded) = load_scene_from_str(&dir.join("render.ron"), &scene, &load_options()) else {
        return;
    };
    let options = RenderOptions {
        threads: Some(1),
        debug_view,
    };
    let (framebuffer, _) = render(&loaded.scene, &options);
    let pixels = framebuffer.width() as usize * framebuffer.height() as usize;
    assert_eq!(framebuffer.to_colors().len(), pixels);
    for (i, color) in framebuffer.to_colors().iter().enumerate() {
        assert!(
            color.is_finite() && color.min_element() >= 0.0,
            "pixel {i} is {color} in the scene\n{scene}"
        );
    }
    let image = lampshade::output::to_rgb8(&framebuffer);
    assert_eq!(image.len(), pixels * 3);
}
