//! The rasterizer's contract, checked through the library on scenes built in code:
//! exact coverage, near-plane clipping, perspective-correct interpolation, determinism.

use std::sync::Arc;

use glam::{DMat4, DVec3, Vec3};
use lampshade::mesh::Mesh;
use lampshade::render::raster::{PixelRect, SamplePattern, for_each_covered_pixel, for_each_covered_sample};
use lampshade::render::{FrameBuffer, RenderOptions, geometry::build_frame, render};
use lampshade::scene::{
    BackFaces, Camera, ImageSettings, Light, LightingComponent, LightingModel, Material, MaterialTextures,
    NormalInterpolation, Object, Projection, Scene, Shading,
};

const UNLIT_WHITE: Material = Material {
    ambient: Vec3::ZERO,
    diffuse: Vec3::ONE,
    specular: Vec3::ZERO,
    shininess: 1.0,
    emission: Vec3::ZERO,
    model: LightingModel::Unlit,
    textures: MaterialTextures {
        diffuse: None,
        ambient: None,
        normal: None,
    },
};

fn object(mesh: Mesh, material: Material, shading: Shading) -> Object {
    Object {
        name: "test".into(),
        mesh: Arc::new(mesh),
        transform: DMat4::IDENTITY,
        shading,
        material: Some(material),
        back_faces: BackFaces::ReverseLit,
        component: LightingComponent::All,
        normal_interpolation: NormalInterpolation::Nlerp,
    }
}

/// An orthographic camera mapping world (x, y) in [0, width] × [0, height] onto the image, one
/// unit a pixel, looking down −Z at the plane z = 0.
fn pixel_aligned_scene(width: u32, height: u32, objects: Vec<Object>) -> Scene {
    let center = DVec3::new(f64::from(width) / 2.0, f64::from(height) / 2.0, 0.0);
    Scene {
        image: ImageSettings {
            width,
            height,
            background: Vec3::ZERO,
            samples: 1,
            mip_bias: 0.0,
        },
        camera: Camera {
            eye: center + DVec3::Z * 10.0,
            target: center,
            up: DVec3::Y,
            projection: Projection::Orthographic {
                height: f64::from(height),
                near: 1.0,
                far: 100.0,
            },
        },
        ambient_light: Vec3::ZERO,
        textures: Vec::new(),
        lights: vec![],
        objects,
    }
}

/// How many triangles cover each pixel centre.
fn coverage_counts(scene: &Scene) -> Vec<u32> {
    let (width, height) = (scene.image.width, scene.image.height);
    let frame = build_frame(scene, SamplePattern::SINGLE, None, Vec::new());
    let rect = PixelRect {
        x0: 0,
        y0: 0,
        x1: width,
        y1: height,
    };
    let mut counts = vec![0; (width * height) as usize];
    for triangle in frame.raster_triangles() {
        for_each_covered_pixel(triangle, rect, |x, y, _| counts[(y * width + x) as usize] += 1);
    }
    counts
}

fn flat_mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    Mesh {
        normals: vec![Vec3::Z; positions.len()],
        positions,
        triangles,
        ..Mesh::default()
    }
}

/// A grid of `n × n` cells over [lo, hi]², interior vertices jittered (deterministically) so
/// edges run at every angle, each cell split into two triangles along a varying diagonal.
fn jittered_grid(n: u32, lo: f32, hi: f32, jitter: f32, seed: u32) -> Mesh {
    let mut state = seed.wrapping_mul(2654435761).wrapping_add(1);
    let mut random = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        (state as f32 / u32::MAX as f32) * 2.0 - 1.0
    };
    let step = (hi - lo) / n as f32;
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let interior = i > 0 && i < n && j > 0 && j < n;
            let (dx, dy) = if interior {
                (random() * jitter * step, random() * jitter * step)
            } else {
                (0.0, 0.0)
            };
            positions.push(Vec3::new(
                lo + i as f32 * step + dx,
                lo + j as f32 * step + dy,
                0.0,
            ));
        }
    }
    let index = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
            if (i + j) % 2 == 0 {
                triangles.extend([[a, b, c], [a, c, d]]);
            } else {
                triangles.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    flat_mesh(positions, triangles)
}

#[test]
fn a_mesh_tiling_the_viewport_covers_every_pixel_exactly_once() {
    for (seed, offset) in [(1, 0.0), (2, 0.25), (3, 0.5), (4, 1.0 / 3.0), (5, 0.999)] {
        let mut mesh = jittered_grid(40, -3.0, 131.0, 0.2, seed);
        for p in &mut mesh.positions {
            *p += Vec3::new(offset, offset * 0.7, 0.0);
        }
        let counts = coverage_counts(&pixel_aligned_scene(
            128,
            96,
            vec![object(mesh, UNLIT_WHITE, Shading::Flat)],
        ));
        let wrong: Vec<usize> = (0..counts.len()).filter(|&i| counts[i] != 1).collect();
        assert!(
            wrong.is_empty(),
            "seed {seed}, offset {offset}: {} pixels not covered exactly once, first at {:?}",
            wrong.len(),
            wrong.first()
        );
    }
}

#[test]
fn every_sample_of_every_pattern_is_covered_exactly_once() {
    for samples in [2, 4, 8, 16] {
        let pattern = SamplePattern::new(samples).unwrap();
        let mesh = jittered_grid(24, -3.0, 67.0, 0.2, samples);
        let scene = pixel_aligned_scene(64, 48, vec![object(mesh, UNLIT_WHITE, Shading::Flat)]);
        let frame = build_frame(&scene, pattern, None, Vec::new());
        let rect = PixelRect {
            x0: 0,
            y0: 0,
            x1: 64,
            y1: 48,
        };
        let mut counts = vec![0u32; 64 * 48 * samples as usize];
        for triangle in frame.raster_triangles() {
            for_each_covered_sample(triangle, rect, pattern, |x, y, sample, _| {
                counts[(y * 64 + x) as usize * samples as usize + sample] += 1
            });
        }
        assert!(
            counts.iter().all(|&c| c == 1),
            "{samples} samples: {:?}",
            counts.iter().max()
        );
    }
}

#[test]
fn multisampling_averages_partly_covered_pixels() {
    // A white square whose right edge runs down the middle of pixel column 10.
    let positions = vec![
        Vec3::new(-5.0, -5.0, 0.0),
        Vec3::new(10.5, -5.0, 0.0),
        Vec3::new(10.5, 40.0, 0.0),
        Vec3::new(-5.0, 40.0, 0.0),
    ];
    let square = flat_mesh(positions, vec![[0, 1, 2], [0, 2, 3]]);
    let mut scene = pixel_aligned_scene(20, 16, vec![object(square, UNLIT_WHITE, Shading::Flat)]);
    scene.image.samples = 16;
    let (image, _) = render(&scene, &RenderOptions::default());
    for y in 0..16 {
        let row = |x: u32| image.pixel(x, y).x;
        assert_eq!(row(9), 1.0);
        assert_eq!(row(11), 0.0);
        // 8 of the 16 samples lie left of the centre, 1 on it, 7 right of it.
        assert!((0.45..=0.6).contains(&row(10)), "row {y}: {}", row(10));
    }
    scene.image.samples = 1;
    let (aliased, _) = render(&scene, &RenderOptions::default());
    assert!(aliased.to_colors().iter().all(|c| c.x == 0.0 || c.x == 1.0));
}

#[test]
fn a_fan_of_thin_triangles_around_one_vertex_covers_its_disc_once() {
    // 10,000 slivers around the centre of the image: every pixel inside the fan's outer polygon
    // is covered once, none twice.
    let center = Vec3::new(64.3, 48.6, 0.0);
    let n = 10_000;
    let radius = 200.0;
    let mut positions = vec![center];
    for k in 0..n {
        let angle = k as f32 / n as f32 * std::f32::consts::TAU;
        positions.push(center + Vec3::new(angle.cos(), angle.sin(), 0.0) * radius);
    }
    let triangles = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
    let counts = coverage_counts(&pixel_aligned_scene(
        128,
        96,
        vec![object(
            flat_mesh(positions, triangles),
            UNLIT_WHITE,
            Shading::Flat,
        )],
    ));
    assert!(
        counts.iter().all(|&c| c == 1),
        "max {:?}, zeros {}",
        counts.iter().max(),
        counts.iter().filter(|&&c| c == 0).count()
    );
}

/// A perspective camera at the origin looking down −Z with a 90° field of view.
fn camera_at_origin(near: f64) -> Camera {
    Camera {
        eye: DVec3::ZERO,
        target: DVec3::new(0.0, 0.0, -1.0),
        up: DVec3::Y,
        projection: Projection::Perspective {
            fov_y_degrees: 90.0,
            near,
            far: 100.0,
        },
    }
}

#[test]
fn a_floor_passing_behind_the_camera_renders_only_its_visible_part() {
    // A floor at y = −1 from 5 units behind the eye to 50 in front. Without clipping, the
    // vertices behind the eye would project to the top of the screen and smear the floor
    // across the sky.
    let positions = vec![
        Vec3::new(-50.0, -1.0, 5.0),
        Vec3::new(50.0, -1.0, 5.0),
        Vec3::new(50.0, -1.0, -50.0),
        Vec3::new(-50.0, -1.0, -50.0),
    ];
    let floor = Mesh {
        normals: vec![Vec3::Y; 4],
        positions,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..Mesh::default()
    };
    let (width, height) = (64, 64);
    let scene = Scene {
        image: ImageSettings {
            width,
            height,
            background: Vec3::ZERO,
            samples: 1,
            mip_bias: 0.0,
        },
        camera: camera_at_origin(0.1),
        ambient_light: Vec3::ZERO,
        textures: Vec::new(),
        lights: vec![],
        objects: vec![object(floor, UNLIT_WHITE, Shading::Flat)],
    };
    let (image, _) = render(&scene, &RenderOptions::default());
    // The far edge (z = −50) projects to y_ndc = −1/50: 0.64 px below the centre line.
    for y in 0..height {
        for x in 0..width {
            let covered = image.is_covered(x, y);
            assert_eq!(covered, y >= 33, "pixel ({x}, {y})");
        }
    }
    assert!(image.to_colors().iter().all(|c| c.is_finite()));
}

#[test]
fn attributes_are_interpolated_perspective_correctly() {
    // A floor strip from z = −1 to z = −9 at y = −1, Gouraud-shaded so that its near edge is
    // black and its far edge white: the colour is linear in depth along the floor, not on
    // screen.
    let positions = vec![
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(1.0, -1.0, -9.0),
        Vec3::new(-1.0, -1.0, -9.0),
    ];
    // Lambert with a light along +Z: N = X gives N·L = 0 (black), N = Z gives 1 (white).
    let normals = vec![Vec3::X, Vec3::X, Vec3::Z, Vec3::Z];
    let strip = Mesh {
        positions,
        normals,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..Mesh::default()
    };
    let lambert = Material {
        model: LightingModel::Lambert,
        ..UNLIT_WHITE
    };
    let (width, height) = (64u32, 64u32);
    let scene = Scene {
        image: ImageSettings {
            width,
            height,
            background: Vec3::ZERO,
            samples: 1,
            mip_bias: 0.0,
        },
        camera: camera_at_origin(0.1),
        ambient_light: Vec3::ZERO,
        textures: Vec::new(),
        lights: vec![Light::Directional {
            direction: -Vec3::Z,
            color: Vec3::ONE,
            shadow: None,
        }],
        objects: vec![object(strip, lambert, Shading::Gouraud)],
    };
    let (image, _) = render(&scene, &RenderOptions::default());
    let x = width / 2;
    let mut checked = 0;
    for y in 34..height - 1 {
        if !image.is_covered(x, y) {
            continue;
        }
        // The row's centre sees the floor at y_ndc = 1 − 2(y + ½)/height = −1/d, d its depth.
        let y_ndc = 1.0 - 2.0 * (y as f32 + 0.5) / height as f32;
        let depth = -1.0 / y_ndc;
        let perspective = (depth - 1.0) / 8.0;
        let screen_linear = (y_ndc + 1.0) / (1.0 - 1.0 / 9.0);
        let got = image.pixel(x, y).x;
        assert!(
            (got - perspective).abs() < 0.01,
            "row {y}: got {got}, perspective-correct {perspective}"
        );
        if (perspective - screen_linear).abs() > 0.1 {
            assert!(
                (got - screen_linear).abs() > 0.05,
                "row {y} looks screen-space interpolated"
            );
            checked += 1;
        }
    }
    assert!(
        checked > 5,
        "the test must visit rows where the two interpolations differ"
    );
}

fn busy_scene() -> Scene {
    let sphere = lampshade::mesh::primitives::sphere(48);
    let mut objects = Vec::new();
    for (i, shading) in [Shading::Flat, Shading::Gouraud, Shading::Phong]
        .into_iter()
        .enumerate()
    {
        let mut o = object(
            sphere.clone(),
            Material {
                specular: Vec3::splat(0.6),
                shininess: 30.0,
                model: LightingModel::BlinnPhong,
                ..Material {
                    ambient: Vec3::splat(0.1),
                    ..UNLIT_WHITE
                }
            },
            shading,
        );
        o.transform = DMat4::from_translation(DVec3::new(i as f64 * 1.5 - 1.5, 0.2 * i as f64, -(i as f64)));
        objects.push(o);
    }
    Scene {
        image: ImageSettings {
            width: 301,
            height: 197,
            background: Vec3::new(0.1, 0.1, 0.1),
            samples: 1,
            mip_bias: 0.0,
        },
        camera: Camera {
            eye: DVec3::new(0.5, 1.0, 5.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            projection: Projection::Perspective {
                fov_y_degrees: 50.0,
                near: 0.1,
                far: 50.0,
            },
        },
        ambient_light: Vec3::splat(0.3),
        textures: Vec::new(),
        lights: vec![
            Light::Directional {
                direction: Vec3::new(-1.0, -1.0, -1.0),
                color: Vec3::ONE,
                shadow: None,
            },
            Light::Point {
                position: DVec3::new(2.0, 2.0, 2.0),
                color: Vec3::new(0.5, 0.4, 0.3),
                attenuation: lampshade::scene::Attenuation {
                    constant: 1.0,
                    linear: 0.1,
                    quadratic: 0.05,
                },
                shadow: None,
            },
        ],
        objects,
    }
}

#[test]
fn the_image_is_bit_identical_for_any_thread_count() {
    for samples in [1, 4] {
        let mut scene = busy_scene();
        scene.image.samples = samples;
        check_thread_independence(&scene);
    }
}

/// A renderer reusing the last frame's buffers gives each frame exactly the image of a fresh
/// render, whatever came before: another scene, more or fewer triangles, another size, other
/// shading modes, more samples.
#[test]
fn reused_buffers_change_no_pixel() {
    let busy = busy_scene();
    let mut gouraud_only = busy_scene();
    gouraud_only.objects.truncate(2);
    gouraud_only.objects[0].shading = Shading::Gouraud;
    gouraud_only.image.width = 173;
    let mut sampled = busy_scene();
    sampled.image.samples = 4;
    let mut renderer = lampshade::render::Renderer::default();
    let options = RenderOptions::default();
    for scene in [&busy, &gouraud_only, &busy, &sampled, &busy, &busy] {
        let (fresh, fresh_stats) = render(scene, &options);
        let stats = renderer.render(scene, &options);
        assert_eq!(renderer.framebuffer(), &fresh);
        assert_eq!(stats.raster_triangles, fresh_stats.raster_triangles);
        assert!(fresh.to_coverage().iter().filter(|&&c| c).count() > 1000);
    }
}

/// Where no triangle reaches, a frame reads its own background, uncovered, whatever an earlier
/// frame drew into the reused buffer there: after a busy scene, the same view with nothing in
/// it, then with one small sphere, each on another background; through every accessor and the
/// 8-bit output.
#[test]
fn a_reused_frame_buffer_shows_no_stale_pixel_where_nothing_is_drawn() {
    // A sphere around the view's whole cone (43° seen from the eye; the corners are 40° off axis).
    let mut busy = busy_scene();
    busy.objects.truncate(1);
    busy.objects[0].transform = DMat4::from_scale(DVec3::splat(3.5));
    let mut empty = busy_scene();
    empty.objects.clear();
    empty.image.background = Vec3::new(0.25, 0.5, 0.75);
    let mut small = busy_scene();
    small.objects.truncate(1);
    small.objects[0].transform = DMat4::from_scale(DVec3::splat(0.2));
    small.image.background = Vec3::new(0.9, 0.0, 0.3);
    let mut renderer = lampshade::render::Renderer::default();
    let options = RenderOptions::default();
    renderer.render(&busy, &options);
    let busy_frame = renderer.framebuffer().clone();
    assert!(
        busy_frame.coverage().all(|covered| covered),
        "the first scene covers every pixel"
    );
    for scene in [&empty, &small] {
        renderer.render(scene, &options);
        let frame = renderer.framebuffer();
        assert!(frame.blank_tiles() > 0);
        assert_eq!(frame, &render(scene, &options).0);
        let image = lampshade::output::to_rgb8(frame);
        let background = scene
            .image
            .background
            .to_array()
            .map(lampshade::output::quantize_channel);
        for y in 0..frame.height() {
            for x in 0..frame.width() {
                if !frame.is_covered(x, y) {
                    assert_eq!(frame.pixel(x, y), scene.image.background, "({x}, {y})");
                    assert_eq!(image.get_pixel(x, y).0, background, "({x}, {y})");
                }
            }
        }
        let dense = FrameBuffer::from_pixels(
            frame.width(),
            frame.height(),
            frame.to_colors(),
            frame.to_coverage(),
        );
        assert_eq!(image, lampshade::output::to_rgb8(&dense));
    }
    let frame = renderer.framebuffer();
    let covered = frame.coverage().filter(|&covered| covered).count();
    assert!(covered > 100 && covered < busy_frame.coverage().filter(|&c| c).count() / 4);
    assert!(frame.coverage().eq(render(&small, &options).0.coverage()));
    renderer.render(&empty, &options);
    assert!(renderer.framebuffer().coverage().all(|covered| !covered));
    assert!(
        renderer
            .framebuffer()
            .colors()
            .all(|color| color == empty.image.background)
    );
}

fn check_thread_independence(scene: &Scene) {
    let (reference, _) = render(
        scene,
        &RenderOptions {
            threads: Some(1),
            ..Default::default()
        },
    );
    assert!(
        reference.to_coverage().iter().filter(|&&c| c).count() > 1000,
        "the scene must cover pixels"
    );
    for threads in [2, 3, 8] {
        let (image, stats) = render(
            scene,
            &RenderOptions {
                threads: Some(threads),
                ..Default::default()
            },
        );
        assert_eq!(stats.threads, threads);
        let bits = |fb: &lampshade::render::FrameBuffer| {
            fb.to_colors()
                .iter()
                .flat_map(|c| c.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        assert!(
            bits(&image) == bits(&reference),
            "{threads} threads differ from 1"
        );
    }
}

/// One square at z = 0 facing +Z (counter-clockwise from +Z), seen from −Z: from behind.
fn square_seen_from_behind(style: impl Fn(&mut Object)) -> FrameBuffer {
    let positions = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let mut square = object(
        flat_mesh(positions, vec![[0, 1, 2], [0, 2, 3]]),
        Material {
            model: LightingModel::Lambert,
            ambient: Vec3::splat(0.1),
            ..UNLIT_WHITE
        },
        Shading::Phong,
    );
    style(&mut square);
    let scene = Scene {
        image: ImageSettings {
            width: 8,
            height: 8,
            background: Vec3::new(0.0, 1.0, 0.0),
            samples: 1,
            mip_bias: 0.0,
        },
        camera: Camera {
            eye: DVec3::new(0.0, 0.0, -5.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            projection: Projection::Perspective {
                fov_y_degrees: 10.0,
                near: 0.1,
                far: 10.0,
            },
        },
        ambient_light: Vec3::ONE,
        textures: Vec::new(),
        lights: vec![
            // Red from the viewer's side (−Z), blue from the other side (+Z).
            Light::Directional {
                direction: Vec3::Z,
                color: Vec3::new(1.0, 0.0, 0.0),
                shadow: None,
            },
            Light::Directional {
                direction: -Vec3::Z,
                color: Vec3::new(0.0, 0.0, 1.0),
                shadow: None,
            },
        ],
        objects: vec![square],
    };
    render(&scene, &RenderOptions::default()).0
}

#[test]
fn back_face_modes_light_the_back_side_as_documented() {
    let center = |mode: BackFaces| square_seen_from_behind(|o| o.back_faces = mode).to_colors()[4 * 8 + 4];
    let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-4;
    // Two-sided: the normal turns towards the viewer, so the red light on the viewer's side lights it.
    assert!(
        close(center(BackFaces::ReverseLit), Vec3::new(1.1, 0.1, 0.1)),
        "{}",
        center(BackFaces::ReverseLit)
    );
    // One-sided: the normal still points away, towards the blue light.
    assert!(
        close(center(BackFaces::Lit), Vec3::new(0.1, 0.1, 1.1)),
        "{}",
        center(BackFaces::Lit)
    );
    // Not lit: ambient only.
    assert!(
        close(center(BackFaces::Unlit), Vec3::splat(0.1)),
        "{}",
        center(BackFaces::Unlit)
    );
    // Culled: the background shows.
    assert_eq!(center(BackFaces::Cull), Vec3::new(0.0, 1.0, 0.0));
}

#[test]
fn constant_shading_gives_one_colour_per_object_and_components_select_terms() {
    let sphere = lampshade::mesh::primitives::sphere(24);
    let material = Material {
        ambient: Vec3::new(0.2, 0.0, 0.0),
        diffuse: Vec3::new(0.0, 0.7, 0.0),
        specular: Vec3::new(0.0, 0.0, 0.5),
        shininess: 10.0,
        emission: Vec3::ZERO,
        model: LightingModel::Phong,
        textures: MaterialTextures::default(),
    };
    let scene_with = |configure: &dyn Fn(&mut Object)| {
        let mut o = object(sphere.clone(), material, Shading::Phong);
        configure(&mut o);
        Scene {
            image: ImageSettings {
                width: 40,
                height: 40,
                background: Vec3::ZERO,
                samples: 1,
                mip_bias: 0.0,
            },
            camera: Camera {
                eye: DVec3::new(0.0, 0.0, 4.0),
                target: DVec3::ZERO,
                up: DVec3::Y,
                projection: Projection::Perspective {
                    fov_y_degrees: 40.0,
                    near: 0.1,
                    far: 10.0,
                },
            },
            ambient_light: Vec3::ONE,
            textures: Vec::new(),
            lights: vec![Light::Directional {
                direction: Vec3::new(-0.3, -0.4, -1.0),
                color: Vec3::ONE,
                shadow: None,
            }],
            objects: vec![o],
        }
    };
    let constant = render(
        &scene_with(&|o| o.shading = Shading::Constant),
        &RenderOptions::default(),
    )
    .0;
    let covered: Vec<Vec3> = constant
        .to_colors()
        .iter()
        .zip(&constant.to_coverage())
        .filter(|(_, c)| **c)
        .map(|(c, _)| *c)
        .collect();
    assert!(covered.len() > 300);
    assert!(
        covered.iter().all(|c| *c == covered[0]),
        "constant shading must be one colour"
    );

    for (component, channel) in [
        (LightingComponent::Ambient, 0),
        (LightingComponent::Diffuse, 1),
        (LightingComponent::Specular, 2),
    ] {
        let image = render(
            &scene_with(&|o| o.component = component),
            &RenderOptions::default(),
        )
        .0;
        let total: Vec3 = image.to_colors().iter().copied().sum();
        for other in 0..3 {
            if other == channel {
                assert!(total[other] > 1.0, "{component:?} shows nothing");
            } else {
                assert_eq!(total[other], 0.0, "{component:?} leaks channel {other}");
            }
        }
    }
}

/// A floor seen from straight above (8 pixels per unit), a cube floating over it, and a
/// directional light at 45° from +X: the cube's shadow falls on x ∈ [1, 3].
fn shadow_scene(shadow: Option<lampshade::scene::ShadowSettings>) -> Scene {
    let lambert = Material {
        model: LightingModel::Lambert,
        ambient: Vec3::splat(0.2),
        ..UNLIT_WHITE
    };
    let mut floor = object(lampshade::mesh::primitives::plane(), lambert, Shading::Phong);
    floor.transform = DMat4::from_scale(DVec3::splat(4.0));
    let mut cube = object(lampshade::mesh::primitives::cube(), lambert, Shading::Phong);
    cube.transform =
        DMat4::from_translation(DVec3::new(0.0, 2.0, 0.0)) * DMat4::from_scale(DVec3::splat(0.5));
    Scene {
        image: ImageSettings {
            width: 64,
            height: 64,
            background: Vec3::ZERO,
            samples: 1,
            mip_bias: 0.0,
        },
        camera: Camera {
            eye: DVec3::new(0.0, 10.0, 0.0),
            target: DVec3::ZERO,
            up: DVec3::NEG_Z,
            projection: Projection::Orthographic {
                height: 8.0,
                near: 1.0,
                far: 20.0,
            },
        },
        ambient_light: Vec3::ONE,
        textures: Vec::new(),
        lights: vec![Light::Directional {
            direction: Vec3::new(1.0, -1.0, 0.0).normalize(),
            color: Vec3::ONE,
            shadow,
        }],
        objects: vec![floor, cube],
    }
}

#[test]
fn shadows_fall_where_the_geometry_says_and_nowhere_else() {
    let lit = render(&shadow_scene(None), &RenderOptions::default()).0;
    let settings = lampshade::scene::ShadowSettings {
        resolution: 512,
        bias: 1.0,
        filter_radius: 1,
    };
    let shadowed = render(&shadow_scene(Some(settings)), &RenderOptions::default()).0;
    let floor_lit = 0.2 + std::f32::consts::FRAC_1_SQRT_2;
    let mut in_shadow = 0;
    for y in 0..64u32 {
        for x in 0..64u32 {
            // World coordinates of the pixel centre on the floor.
            let (wx, wz) = ((x as f32 + 0.5) / 8.0 - 4.0, (y as f32 + 0.5) / 8.0 - 4.0);
            let under_cube = wx.abs() < 0.55 && wz.abs() < 0.55;
            let shadow_core = (1.15..2.85).contains(&wx) && wz.abs() < 0.4;
            let shadow_band = (0.85..3.15).contains(&wx) && wz.abs() < 0.6;
            if under_cube {
                continue;
            }
            if shadow_core {
                // Ambient only: the light is blocked.
                assert!(
                    (shadowed.pixel(x, y).x - 0.2).abs() < 1e-5,
                    "({wx}, {wz}) should be in shadow: {}",
                    shadowed.pixel(x, y)
                );
                in_shadow += 1;
            } else if !shadow_band {
                // No acne: everywhere else exactly as without shadows.
                assert_eq!(shadowed.pixel(x, y), lit.pixel(x, y), "({wx}, {wz}) is darkened");
                assert!((lit.pixel(x, y).x - floor_lit).abs() < 1e-5);
            }
        }
    }
    assert!(in_shadow > 60, "{in_shadow}");
}

#[test]
fn a_texture_modulates_the_diffuse_colour_through_perspective_correct_uvs() {
    use lampshade::scene::TextureBinding;
    use lampshade::texture::{Sampler, Texture};
    use std::sync::Arc;
    // A 2×2 texture: red, green / blue, white.
    let texels = vec![
        glam::Vec4::new(1.0, 0.0, 0.0, 1.0),
        glam::Vec4::new(0.0, 1.0, 0.0, 1.0),
        glam::Vec4::new(0.0, 0.0, 1.0, 1.0),
        glam::Vec4::ONE,
    ];
    let texture = Arc::new(Texture::from_texels(2, 2, texels).unwrap());
    // The quad covers the 64×64 image; (0, 0) of the texture is its top-left corner.
    let mut quad = flat_mesh(
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(64.0, 0.0, 0.0),
            Vec3::new(64.0, 64.0, 0.0),
            Vec3::new(0.0, 64.0, 0.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    quad.uvs = vec![
        glam::Vec2::new(0.0, 1.0),
        glam::Vec2::new(1.0, 1.0),
        glam::Vec2::new(1.0, 0.0),
        glam::Vec2::ZERO,
    ];
    let mut material = Material {
        diffuse: Vec3::splat(0.5),
        ..UNLIT_WHITE
    };
    material.textures.diffuse = Some(TextureBinding {
        texture: 0,
        uv_set: 0,
        sampler: Sampler::default(),
        scale: 1.0,
    });
    for shading in [Shading::Phong, Shading::Gouraud, Shading::Flat] {
        let mut scene = pixel_aligned_scene(64, 64, vec![object(quad.clone(), material, shading)]);
        scene.textures = vec![texture.clone()];
        let (image, _) = render(&scene, &RenderOptions::default());
        let at = |x: u32, y: u32| image.pixel(x, y);
        // Pixel centres at texel centres read the texel exactly, times k_d = 0.5.
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 0.02;
        assert!(
            close(at(16, 16), Vec3::new(0.5, 0.0, 0.0)),
            "{shading:?}: {}",
            at(16, 16)
        );
        assert!(
            close(at(48, 16), Vec3::new(0.0, 0.5, 0.0)),
            "{shading:?}: {}",
            at(48, 16)
        );
        assert!(
            close(at(16, 48), Vec3::new(0.0, 0.0, 0.5)),
            "{shading:?}: {}",
            at(16, 48)
        );
        assert!(close(at(48, 48), Vec3::splat(0.5)), "{shading:?}: {}", at(48, 48));
    }
}
