//! `lampshade report speed-error --knobs`: the approximation knobs a scene actually uses, swept
//! one at a time around the scene's own settings, each point timed and measured against one
//! reference of the scene.
//!
//! The knobs, each only when the scene has what it tunes:
//! - the shading mode (Flat, Gouraud, Phong) of every object at once, and of each object on
//!   its own when there are several (`shading of NAME`);
//! - Nlerp against Slerp (when an object is Phong-shaded);
//! - the tessellation of `Sphere` objects (`Sphere(N)`, textured or not);
//! - the shadow map's resolution, PCF radius and bias (every shadow-casting light at once);
//! - the mip bias (when the scene has textures);
//! - the samples per pixel.
//!
//! The reference is rendered once with 4×4 stratified samples per pixel (the box filter every
//! sample count approaches) and level-0 textures, so each point's error includes its aliasing
//! and its mipmap blur as well as its shading and shadow error. Besides the whole image's
//! error, each point's error is measured where it matters ([`crate::metrics::regions`]: shadow
//! boundaries, the highlight's peak, texture detail). Each knob gets a one-line
//! recommendation: the cheapest value whose FLIP 99th percentile stays within 0.005 of the
//! scene's own setting, and the most accurate value if it beats the scene's by more. With
//! `maps`, each point also gets a heat map of its FLIP error ([`super::maps`]).

use std::fmt::Write as _;
use std::sync::Arc;
use std::time::{Duration, Instant};

use image::RgbImage;

use super::maps;
use super::plot::{self, PlotPoint, Series, TimeErrorChart};
use crate::mesh::primitives;
use crate::metrics::regions::{RegionError, Regions, WhereItMatters};
use crate::metrics::{ErrorMetrics, compare, flip_map};
use crate::reference::{
    ReferenceOptions, Shape, recognize_shape, recognize_textured_shape, render_reference_with,
};
use crate::render::{RenderOptions, render};
use crate::scene::{Light, NormalInterpolation, Scene, Shading, ShadowSettings};

/// One point of the knob sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct KnobPoint {
    pub knob: String,
    pub value: String,
    /// The scene's own setting.
    pub current: bool,
    /// Median wall time of a render.
    pub time: Duration,
    pub error: ErrorMetrics,
    /// The error in the regions where it matters most.
    pub regions: WhereItMatters,
    /// No other point of the whole sweep is both faster and more accurate (FLIP p99).
    pub pareto: bool,
    /// The heat map of the point's error (with [`KnobPlan::maps`]).
    pub heat_map: Option<RgbImage>,
}

impl KnobPoint {
    /// The name of the point's heat map file.
    pub fn map_file_name(&self) -> String {
        maps::map_file_name(&self.knob, &self.value)
    }
}

/// How wide the sweep is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KnobPlan {
    pub runs: u32,
    pub quick: bool,
    /// Make a heat map of each point's error.
    pub maps: bool,
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
fn variants(scene: &Scene, plan: KnobPlan) -> Vec<(String, String, bool, Scene)> {
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
        out.push(("shading".to_string(), name.to_string(), current, variant));
    }
    if scene.objects.len() > 1 {
        for (index, object) in scene.objects.iter().enumerate() {
            let knob = format!("shading of {}", object_label(scene, index));
            for (name, shading) in modes {
                let mut variant = scene.clone();
                variant.objects[index].shading = shading;
                out.push((knob.clone(), name.to_string(), object.shading == shading, variant));
            }
        }
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
            out.push((
                "normal interpolation".to_string(),
                name.to_string(),
                current,
                variant,
            ));
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
                "sphere tessellation".to_string(),
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
                "shadow-map resolution".to_string(),
                resolution.to_string(),
                resolution == settings.resolution,
                with(&|s| s.resolution = resolution),
            ));
        }
        let radii: &[u32] = if plan.quick { &[0, 1] } else { &[0, 1, 2, 3] };
        for radius in with_current(radii, settings.filter_radius) {
            out.push((
                "PCF radius".to_string(),
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
                "shadow bias".to_string(),
                bias.to_string(),
                bias == settings.bias,
                with(&|s| s.bias = bias),
            ));
        }
    }
    let textured = !scene.textures.is_empty() || scene.objects.iter().any(|o| !o.mesh.textures.is_empty());
    if textured {
        let biases: &[f32] = if plan.quick {
            &[0.0, 1.0]
        } else {
            &[-1.0, -0.5, 0.0, 0.5, 1.0, 2.0]
        };
        for bias in with_current(biases, scene.image.mip_bias) {
            let mut variant = scene.clone();
            variant.image.mip_bias = bias;
            out.push((
                "mip bias".to_string(),
                bias.to_string(),
                bias == scene.image.mip_bias,
                variant,
            ));
        }
    }
    let samples: &[u32] = if plan.quick { &[1, 4] } else { &[1, 2, 4, 8, 16] };
    for count in with_current(samples, scene.image.samples) {
        let mut variant = scene.clone();
        variant.image.samples = count;
        out.push((
            "samples per pixel".to_string(),
            count.to_string(),
            count == scene.image.samples,
            variant,
        ));
    }
    out
}

/// How an object is named in a knob: its name (`object N` when the scene gives none), with
/// its place in the list where another object has the same name.
fn object_label(scene: &Scene, index: usize) -> String {
    let name = &scene.objects[index].name;
    if scene.objects.iter().filter(|o| &o.name == name).count() > 1 {
        format!("{name} (object {index})")
    } else {
        name.clone()
    }
}

/// Sweeps the knobs `scene` uses; `progress` sees every point as it is measured.
pub fn sweep_knobs(
    scene: &Scene,
    plan: KnobPlan,
    threads: Option<usize>,
    mut progress: impl FnMut(&KnobPoint),
) -> (Vec<KnobPoint>, Duration) {
    let started = Instant::now();
    let rendered = render_reference_with(
        scene,
        &ReferenceOptions {
            threads,
            samples: Some(REFERENCE_STRATA),
            features: true,
            ..ReferenceOptions::default()
        },
    );
    let reference_time = started.elapsed();
    let reference = rendered.framebuffer;
    let regions = Regions::find(&reference, &rendered.features);
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
        let flip = flip_map(&reference, &image);
        let heat_map = plan.maps.then(|| {
            let (values, scale) = maps::error_values(&reference, &image, flip.as_deref());
            maps::heat_map(&values, image.width(), image.height(), scale)
        });
        points.push(KnobPoint {
            knob,
            value,
            current,
            time: times[times.len() / 2],
            error: compare(&reference, &image).expect("same size"),
            regions: regions.errors(&reference, &image, flip.as_deref()),
            pareto: false,
            heat_map,
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
    let mut knobs: Vec<&str> = Vec::new();
    for point in points {
        if !knobs.contains(&point.knob.as_str()) {
            knobs.push(&point.knob);
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
                "{knob} {} → {} keeps FLIP p99 at {:.3}, within {KEEPS_ERROR} of the scene's {current_error:.3}, and saves {:.1} ms",
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

/// A region's error in a table cell: mean absolute error and FLIP mean, or empty for a region
/// without pixels.
fn region_cell(region: &RegionError) -> String {
    if region.pixels == 0 {
        return String::new();
    }
    match region.flip_mean {
        Some(flip) => format!("{:.2} · {flip:.3}", region.mean_abs),
        None => format!("{:.2}", region.mean_abs),
    }
}

/// The knob table and recommendations in Markdown; `maps` is the heat maps' folder as a link
/// from the Markdown file, when they were written.
pub fn knobs_markdown(points: &[KnobPoint], title: &str, header: &str, maps: Option<&str>) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Speed against error, knob by knob: `{title}`\n");
    let _ = writeln!(out, "{header}\n");
    let _ = writeln!(out, "## Recommendations\n");
    for line in recommendations(points) {
        let _ = writeln!(out, "- {line}");
    }
    if let Some(first) = points.first() {
        let r = &first.regions;
        let _ = writeln!(
            out,
            "\n**Where it matters** (`metrics::regions`; each cell: mean absolute error in levels · FLIP mean): \
             *shadow edge*, {} px where the reference's shadow rays to a light are blocked for some samples \
             and not for others in the pixel or its 8 neighbours; *highlight*, {} px whose reference specular \
             is within {:.0}% of the brightest; *texture detail*, {} px textured in a 3×3 neighbourhood whose \
             reference luma varies by at least {} levels there (shadow edges excluded).",
            r.shadow_boundary.pixels,
            r.highlight.pixels,
            100.0 * crate::metrics::regions::HIGHLIGHT_SHARE,
            r.texture_detail.pixels,
            crate::metrics::regions::TEXTURE_CONTRAST
        );
    }
    let _ = writeln!(
        out,
        "\n## Points\n\n| knob | value | ms | mean abs | max abs | PSNR dB | > 8 | FLIP mean | FLIP p99 | shadow edge | highlight | texture detail | P |{}",
        if maps.is_some() { " map |" } else { "" }
    );
    let _ = writeln!(
        out,
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|{}",
        if maps.is_some() { "---|" } else { "" }
    );
    for p in points {
        let e = &p.error;
        let (flip_mean, flip_99) = e.flip.map_or((String::new(), String::new()), |f| {
            (format!("{:.4}", f.mean), format!("{:.4}", f.percentile_99))
        });
        let map = match maps {
            Some(folder) => {
                let name = p.map_file_name();
                format!(" [map]({folder}/{name}) |")
            }
            None => String::new(),
        };
        let _ = writeln!(
            out,
            "| {} | {}{} | {:.1} | {:.3} | {} | {:.1} | {:.2}% | {} | {} | {} | {} | {} | {} |{map}",
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
            region_cell(&p.regions.shadow_boundary),
            region_cell(&p.regions.highlight),
            region_cell(&p.regions.texture_detail),
            if p.pareto { "P" } else { "" },
        );
    }
    out
}

/// Every point as CSV.
pub fn knobs_csv(points: &[KnobPoint]) -> String {
    let mut out = String::from(
        "knob,value,scene,time_ms,mean_abs,max_abs,psnr_db,share_over_8,flip_mean,flip_p99,\
         shadow_edge_pixels,shadow_edge_mean_abs,shadow_edge_flip_mean,\
         highlight_pixels,highlight_mean_abs,highlight_flip_mean,\
         texture_detail_pixels,texture_detail_mean_abs,texture_detail_flip_mean,pareto\n",
    );
    let region = |r: &RegionError| {
        format!(
            "{},{:.4},{}",
            r.pixels,
            r.mean_abs,
            r.flip_mean.map_or(String::new(), |f| format!("{f:.4}"))
        )
    };
    for p in points {
        let e = &p.error;
        let (flip_mean, flip_99) = e.flip.map_or((String::new(), String::new()), |f| {
            (format!("{:.4}", f.mean), format!("{:.4}", f.percentile_99))
        });
        let _ = writeln!(
            out,
            "{},{},{},{:.3},{:.4},{},{:.2},{:.6},{},{},{},{},{},{}",
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
            region(&p.regions.shadow_boundary),
            region(&p.regions.highlight),
            region(&p.regions.texture_detail),
            p.pareto
        );
    }
    out
}

/// What a plot's vertical axis shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlotError {
    /// FLIP's 99th percentile over the image (mean absolute error without FLIP).
    FlipP99,
    ShadowEdge,
    Highlight,
    TextureDetail,
}

impl PlotError {
    pub const ALL: [PlotError; 4] = [
        PlotError::FlipP99,
        PlotError::ShadowEdge,
        PlotError::Highlight,
        PlotError::TextureDetail,
    ];

    /// The plot's file name.
    pub fn file_name(self) -> &'static str {
        match self {
            PlotError::FlipP99 => "knobs-flip-p99.svg",
            PlotError::ShadowEdge => "knobs-shadow-edge.svg",
            PlotError::Highlight => "knobs-highlight.svg",
            PlotError::TextureDetail => "knobs-texture-detail.svg",
        }
    }

    fn label(self) -> &'static str {
        match self {
            PlotError::FlipP99 => "FLIP 99th percentile",
            PlotError::ShadowEdge => "FLIP mean on shadow edges",
            PlotError::Highlight => "FLIP mean at the highlight peak",
            PlotError::TextureDetail => "FLIP mean on texture detail",
        }
    }

    /// The point's error on this axis; `None` where the region is empty.
    fn of(self, point: &KnobPoint) -> Option<f64> {
        let region = |r: &RegionError| (r.pixels > 0).then(|| r.flip_mean.unwrap_or(r.mean_abs / 255.0));
        match self {
            PlotError::FlipP99 => Some(flip_p99(&point.error)),
            PlotError::ShadowEdge => region(&point.regions.shadow_boundary),
            PlotError::Highlight => region(&point.regions.highlight),
            PlotError::TextureDetail => region(&point.regions.texture_detail),
        }
    }
}

/// Time against `axis`'s error for every point: one colour per knob, the scene's own setting
/// ringed, the Pareto front (by this error) drawn as a line. `None` when no point has this
/// error (the region is empty).
pub fn knobs_plot_svg(points: &[KnobPoint], axis: PlotError, title: &str) -> Option<Result<String, String>> {
    use plotters::style::{Color as _, Palette as _, Palette99, RGBColor};
    // Zero errors cannot sit on a log axis: floor them at a ten-thousandth.
    let shown: Vec<(&KnobPoint, PlotPoint)> = points
        .iter()
        .filter_map(|p| {
            let error = axis.of(p)?.max(1e-4);
            let time_ms = milliseconds(p.time);
            Some((
                p,
                PlotPoint {
                    time_ms,
                    error,
                    ringed: p.current,
                    label: None,
                },
            ))
        })
        .collect();
    if shown.is_empty() {
        return None;
    }
    let front = plot::pareto_front(shown.iter().map(|(_, q)| (q.time_ms, q.error)));
    let mut series: Vec<Series> = Vec::new();
    for (p, point) in shown {
        match series.iter_mut().find(|s| s.name == p.knob) {
            Some(existing) => existing.points.push(point),
            None => {
                let (r, g, b) = Palette99::pick(series.len()).rgb();
                let colour = RGBColor(r, g, b);
                series.push(Series {
                    name: p.knob.clone(),
                    colour,
                    points: vec![point],
                });
            }
        }
    }
    let chart = TimeErrorChart {
        title,
        size: (960, 640),
        error_axis: axis.label(),
        series,
        front,
        front_legend: "Pareto front (ringed: the scene's own setting)",
    };
    Some(chart.to_svg())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::load_scene_from_str;

    /// A shadowed sphere on a plane: the sweep has the knobs the scene uses (and no others),
    /// each object's shading on its own, each knob with the scene's own setting marked, a
    /// reference-sized error per point and on the shadow's edge, a heat map per point, a
    /// recommendation per knob, and well-formed plots.
    #[test]
    fn sweeps_the_knobs_a_scene_uses() {
        let scene = load_scene_from_str(
            std::path::Path::new("knobs.ron"),
            "(image: (width: 64, height: 48), \
             camera: Perspective(eye: (0, 4, 5), target: (0, 0, 0), fov: 40), \
             lights: [Spot(position: (1, 5, 1), direction: (-0.2, -1, -0.2), cutoff: 40, shadows: true, \
                           shadow_map: (resolution: 16))], \
             objects: [(mesh: Sphere(segments: 32), translate: (0, 1, 0), shading: Gouraud), \
                       (mesh: Plane, scale: 3)])",
            &crate::scene::LoadOptions::default(),
        )
        .unwrap_or_else(|error| panic!("{:?}", error.diagnostics))
        .scene;
        let plan = KnobPlan {
            runs: 1,
            quick: true,
            maps: true,
        };
        let mut seen = 0;
        let (points, _) = sweep_knobs(&scene, plan, Some(2), |_| seen += 1);
        assert_eq!(seen, points.len());
        let knobs: Vec<&str> = points.iter().map(|p| p.knob.as_str()).collect();
        for knob in [
            "shading",
            "normal interpolation",
            "sphere tessellation",
            "shadow-map resolution",
            "PCF radius",
            "shadow bias",
            "samples per pixel",
            "shading of object 0",
            "shading of object 1",
        ] {
            assert!(knobs.contains(&knob), "{knob}: {knobs:?}");
        }
        // No texture, no mip bias.
        assert!(!knobs.contains(&"mip bias"), "{knobs:?}");
        // Each object's three modes, the scene's own marked: the sphere is Gouraud, the plane
        // Phong (the default); only that object's shading differs from the scene.
        for (object, own) in [("object 0", "Gouraud"), ("object 1", "Phong")] {
            let group: Vec<&KnobPoint> = points
                .iter()
                .filter(|p| p.knob == format!("shading of {object}"))
                .collect();
            let values: Vec<&str> = group.iter().map(|p| p.value.as_str()).collect();
            assert_eq!(values, ["Flat", "Gouraud", "Phong"], "{object}");
            let current: Vec<&str> = group
                .iter()
                .filter(|p| p.current)
                .map(|p| p.value.as_str())
                .collect();
            assert_eq!(current, [own], "{object}");
        }
        let error_of = |knob: &str, value: &str| {
            let point = points
                .iter()
                .find(|p| p.knob == knob && p.value == value)
                .unwrap();
            point.error.mean_abs_all()
        };
        // The plane's own setting is the scene; a flat sphere is worse than a Phong one.
        assert_eq!(
            error_of("shading of object 1", "Phong"),
            error_of("shading of object 0", "Gouraud")
        );
        assert!(error_of("shading of object 0", "Flat") > error_of("shading of object 0", "Phong"));
        assert!(points.iter().any(|p| p.current && p.value == "Sphere(32)"));
        // The spot light's shadow of the sphere on the plane has edge pixels, and the scene's
        // blocky 16-texel map errs more there than a finer one.
        let edge = |value: &str| {
            let point = points
                .iter()
                .find(|p| p.knob == "shadow-map resolution" && p.value == value)
                .unwrap();
            point.regions.shadow_boundary
        };
        assert!(
            points
                .iter()
                .any(|p| p.current && p.knob == "shadow-map resolution" && p.value == "16")
        );
        assert!(edge("16").pixels > 20, "{:?}", edge("16"));
        assert!(
            edge("16").mean_abs > edge("1024").mean_abs,
            "{:?} {:?}",
            edge("16"),
            edge("1024")
        );
        // A heat map per point, the image's size and the legend.
        for point in &points {
            let map = point.heat_map.as_ref().expect("maps asked for");
            assert_eq!(map.dimensions(), (64, 48 + maps::LEGEND_HEIGHT));
        }
        let names: std::collections::HashSet<String> = points.iter().map(KnobPoint::map_file_name).collect();
        assert_eq!(names.len(), points.len(), "one file per point");
        assert!(points.iter().all(|p| p.error.pixels > 500), "{points:?}");
        assert!(points.iter().any(|p| p.pareto));
        let lines = recommendations(&points);
        // "shading" has no current value (the objects differ); every other knob has a line.
        assert_eq!(lines.len(), 8, "{lines:?}");
        let markdown = knobs_markdown(&points, "knobs.ron", "test", Some("maps"));
        assert!(markdown.contains("(scene)") && markdown.contains("## Recommendations"));
        assert!(
            markdown.contains("[map](maps/shadow-map-resolution-1024.png)"),
            "{markdown}"
        );
        let csv = knobs_csv(&points);
        assert_eq!(csv.lines().count(), points.len() + 1);
        let columns = csv.lines().next().unwrap().split(',').count();
        assert!(
            csv.lines().all(|line| line.split(',').count() == columns),
            "{csv}"
        );
        // Every plot with points is well-formed XML with the Pareto front; the empty regions
        // (no texture) have none.
        for axis in PlotError::ALL {
            match knobs_plot_svg(&points, axis, "test") {
                Some(svg) => {
                    let svg = svg.unwrap();
                    roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{axis:?}: {e}"));
                    assert!(svg.contains("Pareto front"), "{axis:?}");
                }
                None => assert_eq!(axis, PlotError::TextureDetail),
            }
        }
    }

    /// A textured scene gets the mip bias knob, around its own bias (0), with texture-detail
    /// pixels whose error grows as the bias blurs the texture.
    #[test]
    fn a_textured_scene_sweeps_the_mip_bias() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mip-bias.ron");
        let scene = load_scene_from_str(
            &path,
            "(image: (width: 96, height: 64), \
             camera: Perspective(eye: (0, 1.2, 4), target: (0, 0, -2), fov: 50), \
             lights: [Directional(direction: (0, -1, -0.3))], \
             objects: [(name: \"floor\", mesh: Plane, scale: 6, \
                        material: (texture: \"../assets/textures/checker.png\"))])",
            &crate::scene::LoadOptions::default(),
        )
        .unwrap_or_else(|error| panic!("{:?}", error.diagnostics))
        .scene;
        let plan = KnobPlan {
            runs: 1,
            quick: true,
            maps: false,
        };
        let (points, _) = sweep_knobs(&scene, plan, Some(2), |_| {});
        let biases: Vec<(&str, bool)> = points
            .iter()
            .filter(|p| p.knob == "mip bias")
            .map(|p| (p.value.as_str(), p.current))
            .collect();
        assert_eq!(biases, [("0", true), ("1", false)]);
        let detail = |value: &str| {
            points
                .iter()
                .find(|p| p.knob == "mip bias" && p.value == value)
                .unwrap()
                .regions
                .texture_detail
        };
        assert!(detail("0").pixels > 50, "{:?}", detail("0"));
        assert!(
            detail("1").mean_abs > detail("0").mean_abs,
            "{:?} {:?}",
            detail("1"),
            detail("0")
        );
        assert!(points.iter().all(|p| p.heat_map.is_none()));
    }
}
