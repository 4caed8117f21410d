//! `lampshade report speed-error --knobs`: the approximation knobs a scene actually uses, swept
//! one at a time around the scene's own settings, each point timed and measured against one
//! reference of the scene.
//!
//! The knobs, each only when the scene has what it tunes:
//! - the shading mode (Flat, Gouraud, Phong; every object at once);
//! - Nlerp against Slerp (when an object is Phong-shaded);
//! - the tessellation of `Sphere` objects (`Sphere(N)`, textured or not);
//! - the shadow map's resolution, PCF radius and bias (every shadow-casting light at once);
//! - the samples per pixel.
//!
//! The reference is rendered once with 4×4 stratified samples per pixel (the box filter every
//! sample count approaches) and level-0 textures, so each point's error includes its aliasing
//! and its mipmap blur as well as its shading and shadow error. Each knob gets a one-line
//! recommendation: the cheapest value whose FLIP 99th percentile stays within 0.005 of the
//! scene's own setting, and the most accurate value if it beats the scene's by more.

use std::fmt::Write as _;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::mesh::primitives;
use crate::metrics::{ErrorMetrics, compare};
use crate::reference::{
    ReferenceOptions, Shape, recognize_shape, recognize_textured_shape, render_reference_with,
};
use crate::render::{RenderOptions, render};
use crate::scene::{Light, NormalInterpolation, Scene, Shading, ShadowSettings};

/// One point of the knob sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct KnobPoint {
    pub knob: &'static str,
    pub value: String,
    /// The scene's own setting.
    pub current: bool,
    /// Median wall time of a render.
    pub time: Duration,
    pub error: ErrorMetrics,
    /// No other point of the whole sweep is both faster and more accurate (FLIP p99).
    pub pareto: bool,
}

/// How wide the sweep is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KnobPlan {
    pub runs: u32,
    pub quick: bool,
}

/// FLIP p99 a cheaper setting may add and still be recommended.
const KEEPS_ERROR: f64 = 0.005;

/// Samples per pixel side of the reference.
const REFERENCE_STRATA: u32 = 4;

/// `values` with `current` added where it is missing, in increasing order.
fn with_current<T: PartialOrd + Copy>(values: &[T], current: T) -> Vec<T> {
    let mut all = values.to_vec();
    if !all.contains(&current) {
        all.push(current);
        all.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    }
    all
}

/// The knob's variants of `scene`: (knob, value, whether it is the scene's own, the scene).
fn variants(scene: &Scene, plan: KnobPlan) -> Vec<(&'static str, String, bool, Scene)> {
    let mut out = Vec::new();
    let modes = [
        ("Flat", Shading::Flat),
        ("Gouraud", Shading::Gouraud),
        ("Phong", Shading::Phong),
    ];
    for (name, shading) in modes {
        let mut variant = scene.clone();
        variant.override_shading(shading);
        let current = scene.objects.iter().all(|o| o.shading == shading);
        out.push(("shading", name.to_string(), current, variant));
    }
    if scene.objects.iter().any(|o| o.shading == Shading::Phong) {
        for (name, interpolation) in [
            ("Nlerp", NormalInterpolation::Nlerp),
            ("Slerp", NormalInterpolation::Slerp),
        ] {
            let mut variant = scene.clone();
            for object in &mut variant.objects {
                object.normal_interpolation = interpolation;
            }
            let current = scene
                .objects
                .iter()
                .filter(|o| o.shading == Shading::Phong)
                .all(|o| o.normal_interpolation == interpolation);
            out.push(("normal interpolation", name.to_string(), current, variant));
        }
    }
    let spheres: Vec<(usize, bool)> = scene
        .objects
        .iter()
        .enumerate()
        .filter_map(|(index, object)| {
            if recognize_shape(&object.mesh) == Some(Shape::Sphere) {
                Some((index, false))
            } else if recognize_textured_shape(&object.mesh) == Some(Shape::Sphere) {
                Some((index, true))
            } else {
                None
            }
        })
        .collect();
    if let Some(&(first, _)) = spheres.first() {
        let current = (scene.objects[first].mesh.positions.len() as f64).sqrt().round() as u32 - 1;
        let segments: &[u32] = if plan.quick {
            &[8, 32]
        } else {
            &[16, 32, 64, 128, 256]
        };
        for n in with_current(segments, current) {
            let (plain, textured) = (
                Arc::new(primitives::sphere(n)),
                Arc::new(primitives::textured_sphere(n)),
            );
            let mut variant = scene.clone();
            for &(index, is_textured) in &spheres {
                variant.objects[index].mesh = Arc::clone(if is_textured { &textured } else { &plain });
            }
            out.push((
                "sphere tessellation",
                format!("Sphere({n})"),
                n == current,
                variant,
            ));
        }
    }
    let shadowed = scene.lights.iter().find_map(Light::shadow);
    if let Some(settings) = shadowed {
        let with = |change: &dyn Fn(&mut ShadowSettings)| {
            let mut variant = scene.clone();
            for light in &mut variant.lights {
                let (Light::Directional { shadow, .. }
                | Light::Point { shadow, .. }
                | Light::Spot { shadow, .. }) = light;
                if let Some(shadow) = shadow {
                    change(shadow);
                }
            }
            variant
        };
        let resolutions: &[u32] = if plan.quick {
            &[256, 1024]
        } else {
            &[256, 512, 1024, 2048, 4096]
        };
        for resolution in with_current(resolutions, settings.resolution) {
            out.push((
                "shadow-map resolution",
                resolution.to_string(),
                resolution == settings.resolution,
                with(&|s| s.resolution = resolution),
            ));
        }
        let radii: &[u32] = if plan.quick { &[0, 1] } else { &[0, 1, 2, 3] };
        for radius in with_current(radii, settings.filter_radius) {
            out.push((
                "PCF radius",
                radius.to_string(),
                radius == settings.filter_radius,
                with(&|s| s.filter_radius = radius),
            ));
        }
        let biases: &[f32] = if plan.quick {
            &[0.5, 2.0]
        } else {
            &[0.25, 0.5, 1.0, 2.0, 4.0]
        };
        for bias in with_current(biases, settings.bias) {
            out.push((
                "shadow bias",
                bias.to_string(),
                bias == settings.bias,
                with(&|s| s.bias = bias),
            ));
        }
    }
    let samples: &[u32] = if plan.quick { &[1, 4] } else { &[1, 2, 4, 8, 16] };
    for count in with_current(samples, scene.image.samples) {
        let mut variant = scene.clone();
        variant.image.samples = count;
        out.push((
            "samples per pixel",
            count.to_string(),
            count == scene.image.samples,
            variant,
        ));
    }
    out
}

/// Sweeps the knobs `scene` uses; `progress` sees every point as it is measured.
pub fn sweep_knobs(
    scene: &Scene,
    plan: KnobPlan,
    threads: Option<usize>,
    mut progress: impl FnMut(&KnobPoint),
) -> (Vec<KnobPoint>, Duration) {
    let started = Instant::now();
    let reference = render_reference_with(
        scene,
        &ReferenceOptions {
            threads,
            samples: Some(REFERENCE_STRATA),
            ..ReferenceOptions::default()
        },
    )
    .framebuffer;
    let reference_time = started.elapsed();
    let options = RenderOptions {
        threads,
        debug_view: None,
    };
    let mut points = Vec::new();
    for (knob, value, current, variant) in variants(scene, plan) {
        let mut times = Vec::new();
        let mut image = None;
        for _ in 0..plan.runs.max(1) {
            let started = Instant::now();
            let (frame, _) = render(&variant, &options);
            times.push(started.elapsed());
            image = Some(frame);
        }
        times.sort();
        let image = image.expect("at least one run");
        points.push(KnobPoint {
            knob,
            value,
            current,
            time: times[times.len() / 2],
            error: compare(&reference, &image).expect("same size"),
            pareto: false,
        });
        progress(points.last().expect("just pushed"));
    }
    mark_pareto(&mut points);
    (points, reference_time)
}

fn flip_p99(error: &ErrorMetrics) -> f64 {
    error
        .flip
        .map_or(error.mean_abs_all() / 255.0, |flip| flip.percentile_99)
}

/// Marks the points no other point beats on both time and FLIP p99.
fn mark_pareto(points: &mut [KnobPoint]) {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        (points[a].time, flip_p99(&points[a].error))
            .partial_cmp(&(points[b].time, flip_p99(&points[b].error)))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut best = f64::INFINITY;
    for index in order {
        let error = flip_p99(&points[index].error);
        points[index].pareto = error < best;
        best = best.min(error);
    }
}

fn milliseconds(duration: Duration) -> f64 {
    duration.as_secs_f64() * 1000.0
}

/// One line per knob: what to change, what it keeps and what it saves (or costs).
pub fn recommendations(points: &[KnobPoint]) -> Vec<String> {
    let mut knobs: Vec<&'static str> = Vec::new();
    for point in points {
        if !knobs.contains(&point.knob) {
            knobs.push(point.knob);
        }
    }
    let mut lines = Vec::new();
    for knob in knobs {
        let group: Vec<&KnobPoint> = points.iter().filter(|p| p.knob == knob).collect();
        let Some(current) = group.iter().find(|p| p.current) else {
            continue;
        };
        let current_error = flip_p99(&current.error);
        let cheapest = group
            .iter()
            .filter(|p| flip_p99(&p.error) <= current_error + KEEPS_ERROR)
            .min_by(|a, b| a.time.cmp(&b.time))
            .expect("the current point qualifies");
        let most_accurate = group
            .iter()
            .min_by(|a, b| flip_p99(&a.error).total_cmp(&flip_p99(&b.error)))
            .expect("not empty");
        let mut line = if cheapest.value != current.value && cheapest.time < current.time {
            format!(
                "{knob} {} → {} keeps FLIP p99 at {:.3} (scene: {current_error:.3}) and saves {:.1} ms",
                current.value,
                cheapest.value,
                flip_p99(&cheapest.error),
                milliseconds(current.time) - milliseconds(cheapest.time)
            )
        } else {
            format!(
                "{knob} {}: nothing cheaper keeps its FLIP p99 ({current_error:.3})",
                current.value
            )
        };
        if most_accurate.value != current.value
            && flip_p99(&most_accurate.error) < current_error - KEEPS_ERROR
        {
            let _ = write!(
                line,
                "; {} lowers FLIP p99 to {:.3} for {:+.1} ms",
                most_accurate.value,
                flip_p99(&most_accurate.error),
                milliseconds(most_accurate.time) - milliseconds(current.time)
            );
        }
        lines.push(line);
    }
    lines
}

/// The knob table and recommendations in Markdown.
pub fn knobs_markdown(points: &[KnobPoint], title: &str, header: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Speed against error, knob by knob: `{title}`\n");
    let _ = writeln!(out, "{header}\n");
    let _ = writeln!(out, "## Recommendations\n");
    for line in recommendations(points) {
        let _ = writeln!(out, "- {line}");
    }
    let _ = writeln!(
        out,
        "\n## Points\n\n| knob | value | ms | mean abs | max abs | PSNR dB | > 8 | FLIP mean | FLIP p99 | P |"
    );
    let _ = writeln!(out, "|---|---|---:|---:|---:|---:|---:|---:|---:|:-:|");
    for p in points {
        let e = &p.error;
        let (flip_mean, flip_99) = e.flip.map_or((String::new(), String::new()), |f| {
            (format!("{:.4}", f.mean), format!("{:.4}", f.percentile_99))
        });
        let _ = writeln!(
            out,
            "| {} | {}{} | {:.1} | {:.3} | {} | {:.1} | {:.2}% | {} | {} | {} |",
            p.knob,
            p.value,
            if p.current { " (scene)" } else { "" },
            milliseconds(p.time),
            e.mean_abs_all(),
            e.max_abs_all(),
            e.psnr_db,
            100.0 * e.share_over_8,
            flip_mean,
            flip_99,
            if p.pareto { "P" } else { "" },
        );
    }
    out
}

/// Every point as CSV.
pub fn knobs_csv(points: &[KnobPoint]) -> String {
    let mut out = String::from(
        "knob,value,scene,time_ms,mean_abs,max_abs,psnr_db,share_over_8,flip_mean,flip_p99,pareto\n",
    );
    for p in points {
        let e = &p.error;
        let (flip_mean, flip_99) = e.flip.map_or((String::new(), String::new()), |f| {
            (format!("{:.4}", f.mean), format!("{:.4}", f.percentile_99))
        });
        let _ = writeln!(
            out,
            "{},{},{},{:.3},{:.4},{},{:.2},{:.6},{},{},{}",
            p.knob,
            p.value,
            p.current,
            milliseconds(p.time),
            e.mean_abs_all(),
            e.max_abs_all(),
            e.psnr_db,
            e.share_over_8,
            flip_mean,
            flip_99,
            p.pareto
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::load_scene_from_str;

    /// A shadowed sphere on a plane: the sweep has the knobs the scene uses (and no others),
    /// each with the scene's own setting marked, a reference-sized error per point, and a
    /// recommendation per knob.
    #[test]
    fn sweeps_the_knobs_a_scene_uses() {
        let scene = load_scene_from_str(
            std::path::Path::new("knobs.ron"),
            "(image: (width: 64, height: 48), \
             camera: Perspective(eye: (0, -5, 3), target: (0, 0, 0), up: (0, 0, 1), fov: 40), \
             lights: [Spot(position: (1, -1, 5), direction: (-0.2, 0.2, -1), cutoff: 40, shadows: true)], \
             objects: [(mesh: Sphere(segments: 32), translate: (0, 0, 1)), \
                       (mesh: Plane, scale: 3, shading: Flat)])",
            &crate::scene::LoadOptions::default(),
        )
        .unwrap_or_else(|error| panic!("{:?}", error.diagnostics))
        .scene;
        let plan = KnobPlan { runs: 1, quick: true };
        let mut seen = 0;
        let (points, _) = sweep_knobs(&scene, plan, Some(2), |_| seen += 1);
        assert_eq!(seen, points.len());
        let knobs: Vec<&str> = points.iter().map(|p| p.knob).collect();
        for knob in [
            "shading",
            "normal interpolation",
            "sphere tessellation",
            "shadow-map resolution",
            "PCF radius",
            "shadow bias",
            "samples per pixel",
        ] {
            assert!(knobs.contains(&knob), "{knob}: {knobs:?}");
        }
        assert!(points.iter().any(|p| p.current && p.value == "Sphere(32)"));
        assert!(points.iter().all(|p| p.error.pixels > 500), "{points:?}");
        assert!(points.iter().any(|p| p.pareto));
        let lines = recommendations(&points);
        // "shading" has no current value (the objects differ); every other knob has a line.
        assert_eq!(lines.len(), 6, "{lines:?}");
        let markdown = knobs_markdown(&points, "knobs.ron", "test");
        assert!(markdown.contains("(scene)") && markdown.contains("## Recommendations"));
        assert_eq!(knobs_csv(&points).lines().count(), points.len() + 1);
    }
}
