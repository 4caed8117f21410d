//! The preview's inspector routes: `GET /api/pick?x=X&y=Y` (the pick JSON of `inspect`, for
//! the image shown), `GET /api/object-mask?object=N` (a PNG, transparent except where object
//! `N` shows, for the page to lay over the image) and the page's script, `/page/pick.js`.
//!
//! Both answer about the image the page shows: the server keeps the `ImageOrigin` each
//! published image came with. Errors are JSON (`{"error": "..."}`) with a 4xx status: 400 for
//! a malformed query, 404 when there is no image to ask about yet, 422 for a pixel outside it.

use std::io::Cursor;

use serde::Serialize;

use crate::inspect::ImageOrigin;
use crate::render::inspect::object_mask;

/// The inspector's script, served as `/page/pick.js`.
const PICK_SCRIPT: &str = include_str!("page/pick.js");

/// The colour of a highlighted pixel in the object mask: the page's accent, half opaque.
const HIGHLIGHT: [u8; 4] = [255, 196, 0, 140];

/// The page's files: `(content type, text)` for a `/page/...` path.
pub fn page_file(path: &str) -> Option<(&'static str, &'static str)> {
    match path {
        "/page/pick.js" => Some(("text/javascript; charset=utf-8", PICK_SCRIPT)),
        _ => None,
    }
}

/// Answers `url` (`/api/pick?...` or `/api/object-mask?...`) about the image `origin` made:
/// `(status, content type, body)`.
pub fn answer(url: &str, origin: Option<&ImageOrigin>) -> (u16, &'static str, Vec<u8>) {
    let (path, query) = url.split_once('?').unwrap_or((url, ""));
    let Some(origin) = origin else {
        return error(404, "no image has been rendered yet in this watch session");
    };
    match path {
        "/api/pick" => {
            let (Some(x), Some(y)) = (parameter(query, "x"), parameter(query, "y")) else {
                return error(
                    400,
                    "expected /api/pick?x=X&y=Y with whole pixel coordinates from 0",
                );
            };
            match origin.pick(x, y) {
                Ok(report) => (200, JSON, report.to_json().into_bytes()),
                Err(problem) => error(422, &problem.to_string()),
            }
        }
        "/api/object-mask" => {
            let objects = origin.scene.objects.len();
            match parameter(query, "object").map(|n| n as usize) {
                Some(object) if object < objects => {
                    let mask = object_mask(&origin.scene, &origin.render_options, object);
                    match mask_png(origin.scene.image.width, origin.scene.image.height, &mask) {
                        Some(png) => (200, "image/png", png),
                        None => error(500, "the mask could not be encoded"),
                    }
                }
                Some(object) => error(
                    422,
                    &format!("object {object} does not exist (the scene has {objects})"),
                ),
                None => error(
                    400,
                    "expected /api/object-mask?object=N with an object index from 0",
                ),
            }
        }
        _ => error(404, "not found"),
    }
}

const JSON: &str = "application/json";

#[derive(Serialize)]
struct ErrorAnswer<'a> {
    error: &'a str,
}

fn error(status: u16, message: &str) -> (u16, &'static str, Vec<u8>) {
    let body = serde_json::to_vec(&ErrorAnswer { error: message }).unwrap_or_default();
    (status, JSON, body)
}

/// The whole number `name=N` of a query string, if it is there and one.
fn parameter(query: &str, name: &str) -> Option<u32> {
    query
        .split('&')
        .filter_map(|pair| pair.split_once('='))
        .find(|(key, _)| *key == name)
        .and_then(|(_, value)| value.parse().ok())
}

/// The mask as an RGBA PNG: [`HIGHLIGHT`] where it is set, transparent elsewhere.
fn mask_png(width: u32, height: u32, mask: &[bool]) -> Option<Vec<u8>> {
    let pixels: Vec<u8> = mask
        .iter()
        .flat_map(|&set| if set { HIGHLIGHT } else { [0; 4] })
        .collect();
    let image = image::RgbaImage::from_raw(width, height, pixels)?;
    let mut png = Cursor::new(Vec::new());
    image.write_to(&mut png, image::ImageFormat::Png).ok()?;
    Some(png.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_parameters_are_whole_numbers() {
        assert_eq!(parameter("x=3&y=40", "y"), Some(40));
        assert_eq!(parameter("x=3&y=40", "x"), Some(3));
        assert_eq!(parameter("x=-3", "x"), None);
        assert_eq!(parameter("x=a", "x"), None);
        assert_eq!(parameter("", "x"), None);
    }

    #[test]
    fn without_an_image_every_question_is_a_json_404() {
        let (status, content_type, body) = answer("/api/pick?x=1&y=1", None);
        assert_eq!((status, content_type), (404, JSON));
        let answer: serde_json::Value = serde_json::from_slice(&body).unwrap();
        assert!(answer["error"].as_str().unwrap().contains("no image"));
    }
}
