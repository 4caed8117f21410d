//! `lampshade lsp` driven over standard input and output as an editor drives it: initialize,
//! open a scene with errors, diagnostics with exact ranges (the scene's and an included
//! library's), completion at several positions, hover, go to definition, the outline, a change
//! that fixes the error, bad requests, shutdown.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// How long any answer may take before the test fails (the checker's first mesh load included).
const PATIENCE: Duration = Duration::from_secs(60);

struct Client {
    child: Child,
    stdin: ChildStdin,
    incoming: Receiver<Value>,
    /// Notifications received while waiting for something else.
    notifications: Vec<Value>,
    next_id: i64,
}

impl Client {
    fn start() -> Client {
        let mut child = Command::new(env!("CARGO_BIN_EXE_lampshade"))
            .arg("lsp")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("lampshade lsp starts");
        let stdin = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (sender, incoming) = mpsc::channel();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(stdout);
            loop {
                let mut length = None;
                loop {
                    let mut line = String::new();
                    if reader.read_line(&mut line).unwrap_or(0) == 0 {
                        return;
                    }
                    let line = line.trim_end();
                    if line.is_empty() {
                        break;
                    }
                    if let Some(value) = line.strip_prefix("Content-Length: ") {
                        length = value.parse::<usize>().ok();
                    }
                }
                let mut body = vec![0; length.expect("a Content-Length header")];
                if reader.read_exact(&mut body).is_err() {
                    return;
                }
                let message: Value = serde_json::from_slice(&body).expect("JSON from the server");
                if sender.send(message).is_err() {
                    return;
                }
            }
        });
        let mut client = Client {
            child,
            stdin,
            incoming,
            notifications: Vec::new(),
            next_id: 1,
        };
        let initialized = client.request("initialize", json!({ "capabilities": {} }));
        let capabilities = &initialized["result"]["capabilities"];
        assert_eq!(capabilities["hoverProvider"], json!(true), "{initialized}");
        assert_eq!(capabilities["definitionProvider"], json!(true));
        client.notify("initialized", json!({}));
        client
    }

    fn send(&mut self, message: &Value) {
        let body = message.to_string();
        write!(self.stdin, "Content-Length: {}\r\n\r\n{body}", body.len()).unwrap();
        self.stdin.flush().unwrap();
    }

    fn notify(&mut self, method: &str, params: Value) {
        self.send(&json!({ "jsonrpc": "2.0", "method": method, "params": params }));
    }

    /// Sends a request and returns the whole response (`result` or `error`).
    fn request(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        self.send(&json!({ "jsonrpc": "2.0", "id": id, "method": method, "params": params }));
        loop {
            let message = self.next_message();
            if message["id"] == json!(id) {
                return message;
            }
            self.notifications.push(message);
        }
    }

    fn next_message(&mut self) -> Value {
        self.incoming
            .recv_timeout(PATIENCE)
            .expect("the server answers in time")
    }

    /// The diagnostics of the first `publishDiagnostics` for `uri` that `wanted` accepts
    /// (earlier ones are skipped: the first stage may publish before the checker).
    fn diagnostics(&mut self, uri: &str, wanted: impl Fn(&[Value]) -> bool) -> Vec<Value> {
        let deadline = Instant::now() + PATIENCE;
        let mut seen = Vec::new();
        loop {
            // Notifications for other files stay for a later call.
            let (mine, others): (Vec<Value>, Vec<Value>) = std::mem::take(&mut self.notifications)
                .into_iter()
                .partition(|m| m["method"] == "textDocument/publishDiagnostics" && m["params"]["uri"] == uri);
            self.notifications = others;
            for message in mine {
                let list = message["params"]["diagnostics"]
                    .as_array()
                    .cloned()
                    .unwrap_or_default();
                if wanted(&list) {
                    return list;
                }
                seen.push(list);
            }
            assert!(
                Instant::now() < deadline,
                "no matching diagnostics for {uri}; saw {seen:#?}"
            );
            let message = self.next_message();
            self.notifications.push(message);
        }
    }

    fn shut_down(mut self) {
        let response = self.request("shutdown", Value::Null);
        assert_eq!(response["result"], Value::Null, "{response}");
        self.notify("exit", Value::Null);
        let status = self.child.wait().unwrap();
        assert!(status.success(), "{status}");
    }
}

fn uri(path: &Path) -> String {
    format!("file://{}", path.display())
}

fn position(line: u32, character: u32) -> Value {
    json!({ "line": line, "character": character })
}

fn at(document: &str, line: u32, character: u32) -> Value {
    json!({ "textDocument": { "uri": document }, "position": position(line, character) })
}

fn range(start: (u32, u32), end: (u32, u32)) -> Value {
    json!({ "start": position(start.0, start.1), "end": position(end.0, end.1) })
}

fn labels(response: &Value) -> Vec<String> {
    response["result"]
        .as_array()
        .map(|items| {
            items
                .iter()
                .map(|item| item["label"].as_str().unwrap_or("").to_owned())
                .collect()
        })
        .unwrap_or_default()
}

const LIBRARY: &str = r#"Materials(materials: {
    "brushed": (base: "chrome", shininess: 20),
    "dull-red": (color: (1, 0, 0), shinyness: 3),
})
"#;

const OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";

/// A scene with one error per line it can have one on.
const SCENE_WITH_ERRORS: &str = r#"(
    image: (width: 64, height: 48),
    objects: [
        (mesh: Cube, shadng: Flat),
    ],
)
"#;

const SCENE: &str = r#"(
    include: ["lib.ron"],
    image: (width: 64, height: 48),
    objects: [
        (mesh: Cube, material: "rubyy"),
        (mesh: Obj("meshes/tri.obj"), material: "brushed"),
    ],
)
"#;

#[test]
fn an_editor_session() {
    let folder = tempfile::tempdir().unwrap();
    let folder = folder.path().canonicalize().unwrap();
    std::fs::create_dir(folder.join("meshes")).unwrap();
    std::fs::write(folder.join("meshes/tri.obj"), OBJ).unwrap();
    std::fs::write(folder.join("lib.ron"), LIBRARY).unwrap();
    let scene_path = folder.join("scene.ron");
    let scene = uri(&scene_path);
    let library = uri(&folder.join("lib.ron"));

    let mut client = Client::start();

    // A syntax-stage error, published at once with the CLI's range and hints.
    client.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": scene, "languageId": "ron", "version": 1, "text": SCENE_WITH_ERRORS } }),
    );
    let diagnostics = client.diagnostics(&scene, |list| !list.is_empty());
    assert_eq!(diagnostics.len(), 1, "{diagnostics:#?}");
    assert_eq!(
        diagnostics[0]["range"],
        range((3, 21), (3, 27)),
        "{diagnostics:#?}"
    );
    assert_eq!(diagnostics[0]["severity"], 1);
    let message = diagnostics[0]["message"].as_str().unwrap();
    assert!(message.starts_with("unknown field `shadng`"), "{message}");
    assert!(message.contains("help: did you mean `shading`?"), "{message}");
    assert!(
        message.contains("shading"),
        "the valid fields are listed: {message}"
    );

    // A change that fixes it clears the diagnostics.
    let fixed = SCENE_WITH_ERRORS.replace("shadng", "shading");
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": scene, "version": 2 }, "contentChanges": [{ "text": fixed }] }),
    );
    client.diagnostics(&scene, |list| list.is_empty());

    // The loader's later stages: an unknown material with its did-you-mean, in the scene, and
    // an unknown field in the included library, published for the library.
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": scene, "version": 3 }, "contentChanges": [{ "text": SCENE }] }),
    );
    let diagnostics = client.diagnostics(&scene, |list| !list.is_empty());
    let library_diagnostics = client.diagnostics(&library, |list| !list.is_empty());
    assert_eq!(library_diagnostics.len(), 1, "{library_diagnostics:#?}");
    assert_eq!(library_diagnostics[0]["range"], range((2, 35), (2, 44)));
    assert!(
        library_diagnostics[0]["message"]
            .as_str()
            .unwrap()
            .contains("unknown field `shinyness`")
    );
    // The library does not parse, so its materials are unknown too; the scene says which.
    let unknown: Vec<&Value> = diagnostics
        .iter()
        .filter(|d| {
            d["message"]
                .as_str()
                .unwrap()
                .starts_with("unknown material `rubyy`")
        })
        .collect();
    assert_eq!(unknown.len(), 1, "{diagnostics:#?}");
    assert_eq!(unknown[0]["range"], range((4, 31), (4, 38)));
    assert!(
        unknown[0]["message"]
            .as_str()
            .unwrap()
            .contains("help: did you mean \"ruby\"?")
    );

    // Mesh files: a missing one and one whose content is broken, located at the mesh like the
    // CLI locates them, the caret's label as related information.
    std::fs::write(
        folder.join("meshes/bad.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    )
    .unwrap();
    let meshes = SCENE
        .replace(
            "(mesh: Cube, material: \"rubyy\")",
            "(mesh: Obj(\"meshes/missing.obj\"))",
        )
        .replace("meshes/tri.obj", "meshes/bad.obj");
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": scene, "version": 4 }, "contentChanges": [{ "text": meshes }] }),
    );
    let diagnostics = client.diagnostics(&scene, |list| {
        list.iter()
            .any(|d| d["message"].as_str().unwrap().contains("missing.obj"))
    });
    let missing = diagnostics
        .iter()
        .find(|d| d["message"].as_str().unwrap().contains("missing.obj"))
        .unwrap();
    assert_eq!(missing["range"], range((4, 19), (4, 39)), "{missing:#}");
    assert!(
        missing["message"]
            .as_str()
            .unwrap()
            .contains("\nhelp: paths are relative"),
        "{missing:#}"
    );
    let broken = diagnostics
        .iter()
        .find(|d| {
            d["message"]
                .as_str()
                .unwrap()
                .contains("bad.obj:4:7: face refers to vertex 9")
        })
        .unwrap_or_else(|| panic!("{diagnostics:#?}"));
    assert_eq!(broken["range"], range((5, 19), (5, 35)), "{broken:#}");
    assert_eq!(
        broken["relatedInformation"][0]["message"],
        "this mesh could not be loaded"
    );

    // Fix the library on disk and touch the scene: everything clears, the library too.
    std::fs::write(folder.join("lib.ron"), LIBRARY.replace("shinyness", "shininess")).unwrap();
    let good = SCENE.replace("rubyy", "ruby");
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": scene, "version": 5 }, "contentChanges": [{ "text": good }] }),
    );
    client.diagnostics(&scene, |list| list.is_empty());
    client.diagnostics(&library, |list| list.is_empty());

    // Completion: the object's fields, with the reference's type and default.
    let text = good.replace("(mesh: Cube, material: \"ruby\")", "(mesh: Cube, )");
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": scene, "version": 6 }, "contentChanges": [{ "text": text }] }),
    );
    let line = 4;
    let completion = client.request("textDocument/completion", at(&scene, line, 21));
    let items = labels(&completion);
    for field in ["shading", "material", "translate", "back_faces"] {
        assert!(items.contains(&field.to_owned()), "{field} in {items:?}");
    }
    assert!(
        !items.contains(&"mesh".to_owned()),
        "`mesh` is written already: {items:?}"
    );
    let shading = completion["result"]
        .as_array()
        .unwrap()
        .iter()
        .find(|item| item["label"] == "shading")
        .unwrap();
    assert_eq!(
        shading["detail"],
        "`Constant`, `Flat`, `Gouraud` or `Phong` (default: `Phong`)"
    );
    assert_eq!(shading["textEdit"]["newText"], "shading: ");
    // Variants after `shading: `.
    let text = good.replace("(mesh: Cube, material: \"ruby\")", "(mesh: Cube, shading: Go)");
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": scene, "version": 7 }, "contentChanges": [{ "text": text }] }),
    );
    let completion = client.request("textDocument/completion", at(&scene, line, 32));
    assert_eq!(labels(&completion), ["Constant", "Flat", "Gouraud", "Phong"]);
    assert_eq!(
        completion["result"][2]["textEdit"]["range"],
        range((4, 30), (4, 32))
    );
    // Material names: the library's, then the presets.
    let text = good.replace("material: \"ruby\"", "material: \"b");
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": scene, "version": 8 }, "contentChanges": [{ "text": text }] }),
    );
    let items = labels(&client.request("textDocument/completion", at(&scene, line, 33)));
    assert_eq!(items[0], "brushed", "{items:?}");
    assert!(items.contains(&"ruby".to_owned()) && items.contains(&"black-plastic".to_owned()));

    // Back to the good scene for hover, definition and the outline.
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": scene, "version": 9 }, "contentChanges": [{ "text": good }] }),
    );
    client.diagnostics(&scene, |list| list.is_empty());
    // Paths relative to the scene: folders, then the OBJ files in them.
    let completion = client.request("textDocument/completion", at(&scene, 5, 20));
    assert_eq!(labels(&completion), ["meshes/"], "{completion}");
    let completion = client.request("textDocument/completion", at(&scene, 5, 27));
    assert_eq!(labels(&completion), ["bad.obj", "tri.obj"]);
    assert_eq!(
        completion["result"][0]["textEdit"]["range"],
        range((5, 27), (5, 27))
    );

    let hover = client.request("textDocument/hover", at(&scene, 2, 14));
    let value = hover["result"]["contents"]["value"].as_str().unwrap();
    assert!(
        value.starts_with("`width`: integer, pixels\n\ndefault: `800`"),
        "{value}"
    );
    assert_eq!(hover["result"]["range"], range((2, 12), (2, 17)));
    let hover = client.request("textDocument/hover", at(&scene, 5, 55));
    let value = hover["result"]["contents"]["value"].as_str().unwrap();
    assert!(value.starts_with("material `brushed`, defined in"), "{value}");
    assert!(
        value.contains("lib.ron") && value.contains("| shininess | 20 |"),
        "{value}"
    );
    let hover = client.request("textDocument/hover", at(&scene, 5, 25));
    let value = hover["result"]["contents"]["value"].as_str().unwrap();
    assert!(
        value.starts_with("`meshes/tri.obj`: 1 triangles, 3 vertices"),
        "{value}"
    );
    assert!(value.contains("texture coordinates: yes"), "{value}");

    let definition = client.request("textDocument/definition", at(&scene, 5, 55));
    assert_eq!(definition["result"]["uri"], library.as_str());
    assert_eq!(definition["result"]["range"], range((1, 4), (1, 13)));
    let definition = client.request("textDocument/definition", at(&scene, 1, 16));
    assert_eq!(definition["result"]["uri"], library.as_str());
    let definition = client.request("textDocument/definition", at(&scene, 5, 25));
    assert_eq!(
        definition["result"]["uri"],
        uri(&folder.join("meshes/tri.obj")).as_str()
    );

    let symbols = client.request(
        "textDocument/documentSymbol",
        json!({ "textDocument": { "uri": scene } }),
    );
    let names: Vec<&str> = symbols["result"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["object 1", "object 2"]);

    // Bad requests get errors, and the server goes on.
    let bad = client.request("textDocument/hover", json!({ "nonsense": true }));
    assert_eq!(bad["error"]["code"], -32602, "{bad}");
    let unknown = client.request("lampshade/nothing", json!({}));
    assert_eq!(unknown["error"]["code"], -32601, "{unknown}");
    let elsewhere = client.request("textDocument/hover", at("file:///not/open.ron", 0, 0));
    assert_eq!(elsewhere["result"], Value::Null);
    for line in 0..10 {
        for character in [0, 3, 17, 40, 1000] {
            let answer = client.request("textDocument/completion", at(&scene, line, character));
            assert!(answer.get("result").is_some(), "{answer}");
            let answer = client.request("textDocument/hover", at(&scene, line, character));
            assert!(answer.get("result").is_some(), "{answer}");
        }
    }

    client.shut_down();
}

/// A material library opened by itself is checked on its unsaved text (syntax, fields, `base`
/// chains), and the edit that fixes it clears the diagnostics.
#[test]
fn a_library_opened_on_its_own_is_checked() {
    let folder = tempfile::tempdir().unwrap();
    let folder = folder.path().canonicalize().unwrap();
    let library_path = folder.join("lib.ron");
    std::fs::write(&library_path, LIBRARY).unwrap();
    let library = uri(&library_path);
    let mut client = Client::start();

    client.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": library, "languageId": "ron", "version": 1, "text": LIBRARY } }),
    );
    let diagnostics = client.diagnostics(&library, |list| !list.is_empty());
    assert_eq!(diagnostics.len(), 1, "{diagnostics:#?}");
    assert_eq!(diagnostics[0]["range"], range((2, 35), (2, 44)));
    let message = diagnostics[0]["message"].as_str().unwrap();
    assert!(message.starts_with("unknown field `shinyness`"), "{message}");

    // Past the syntax: a `base` that loops is found without any scene.
    let looping = LIBRARY
        .replace("shinyness", "shininess")
        .replace("base: \"chrome\"", "base: \"brushed\"");
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": library, "version": 2 }, "contentChanges": [{ "text": looping }] }),
    );
    let diagnostics = client.diagnostics(&library, |list| !list.is_empty());
    let message = diagnostics[0]["message"].as_str().unwrap();
    assert!(
        message.contains("material `brushed` is its own base"),
        "{diagnostics:#?}"
    );

    let fixed = LIBRARY.replace("shinyness", "shininess");
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": library, "version": 3 }, "contentChanges": [{ "text": fixed }] }),
    );
    client.diagnostics(&library, |list| list.is_empty());
    assert_eq!(
        std::fs::read_to_string(&library_path).unwrap(),
        LIBRARY,
        "the file on disk is untouched"
    );
    client.shut_down();
}

/// The preview follows the unsaved buffer: with `lampshade watch --serve` running on a scene the
/// editor has open, a change the editor has not saved shows in the preview (the file and the
/// image file untouched), and closing the document brings the file's image back.
#[test]
fn the_preview_of_a_running_watch_follows_the_unsaved_buffer() {
    use crate::watch::{
        SceneFolder, WatchProcess, http_get, preview_port, render_once, scene_text, wait_for,
    };

    let folder = SceneFolder::new();
    let scene = folder.file("scene.ron");
    let saved = std::fs::read_to_string(&scene).unwrap();
    let watch = WatchProcess::start(
        &folder.path,
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    );
    let port = preview_port(&watch);
    let shown = || {
        let (status, body) = http_get(port, "/image.png", &format!("127.0.0.1:{port}"));
        (status == 200).then(|| image::load_from_memory(&body).unwrap().to_rgb8())
    };
    let file_image = wait_for("the first image", || watch.output(), || folder.image());
    let file_pixels = image::load_from_memory(&file_image).unwrap().to_rgb8();

    let unsaved = scene_text((0.1, 0.9, 0.2));
    let expected_folder = SceneFolder::new();
    expected_folder.write("scene.ron", &unsaved);
    let expected = image::load_from_memory(&render_once(&expected_folder.file("scene.ron")))
        .unwrap()
        .to_rgb8();
    assert_ne!(expected, file_pixels);

    let mut client = Client::start();
    let document = uri(&scene);
    client.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": document, "languageId": "ron", "version": 1, "text": saved } }),
    );
    client.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": document, "version": 2 }, "contentChanges": [{ "text": unsaved }] }),
    );
    wait_for(
        "the unsaved text in the preview",
        || watch.output(),
        || (shown()? == expected).then_some(()),
    );
    assert_eq!(
        std::fs::read_to_string(&scene).unwrap(),
        saved,
        "the scene file was written"
    );
    assert_eq!(
        folder.image().unwrap(),
        file_image,
        "the image file shows the unsaved text"
    );

    client.notify(
        "textDocument/didClose",
        json!({ "textDocument": { "uri": document } }),
    );
    wait_for(
        "the file's image again",
        || watch.output(),
        || (shown()? == file_pixels).then_some(()),
    );
    client.shut_down();
}
