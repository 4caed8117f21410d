//! `lampshade lsp`: a language server for scene files and material libraries, over standard
//! input and output (JSON-RPC, the Language Server Protocol), for any editor with an LSP client.
//!
//! Design:
//! - [`lsp_server`] (the transport rust-analyzer is built on: a connection, a reader and a
//!   writer thread, synchronous messages) with [`lsp_types`]. The request loop is this module's
//!   [`serve`]: one request at a time on one thread, each answered from the open documents'
//!   text ([`documents`]); everything it does per keystroke reads no file except the includes
//!   for material names.
//! - Diagnostics ([`diagnostics`]) come in two stages: the parse on the request thread, the full
//!   load (meshes, textures, with a mesh cache) on a checker thread, newest version only. A
//!   material library (`Materials(...)`) open on its own is checked whole on the request thread
//!   ([`crate::scene::load::check_library_text`]: it reads only its includes).
//! - Completion, hover and navigation read what is at the cursor with the loader's own tolerant
//!   reader ([`cursor`]) and answer from the format's schema, the reference's field tables
//!   ([`crate::scene::field_docs`]) and the loader's material resolution.
//! - Bad input never ends the server: requests whose parameters do not parse get
//!   `InvalidParams`, unknown requests `MethodNotFound`, and a panic while answering (a bug) an
//!   `InternalError` for that request only.

pub mod completion;
pub mod cursor;
pub mod diagnostics;
pub mod documents;
pub mod hover;
pub mod navigation;
pub mod preview;

use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;

use lsp_server::{Connection, ErrorCode, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, DidSaveTextDocument, Notification as _,
};
use lsp_types::request::{Completion, DocumentSymbolRequest, GotoDefinition, HoverRequest, Request as _};
use lsp_types::{
    CompletionOptions, CompletionParams, CompletionResponse, DidChangeTextDocumentParams,
    DidCloseTextDocumentParams, DidOpenTextDocumentParams, DidSaveTextDocumentParams, DocumentSymbolParams,
    DocumentSymbolResponse, GotoDefinitionParams, GotoDefinitionResponse, HoverParams,
    HoverProviderCapability, InitializeParams, OneOf, ServerCapabilities, ServerInfo,
    TextDocumentPositionParams, TextDocumentSyncCapability, TextDocumentSyncKind, TextDocumentSyncOptions,
    TextDocumentSyncSaveOptions, Url,
};
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::cli::{EXIT_BAD_INPUT, EXIT_OK};
use crate::lsp::diagnostics::{Checker, Publisher, to_lsp};
use crate::lsp::documents::{Documents, offset_of};
use crate::lsp::preview::PreviewLink;
use crate::scene::load::{LoadOptions, check_library_text, parse_scene_text};

/// `lampshade lsp`'s arguments.
#[derive(Debug, clap::Args)]
pub struct LspArgs {
    /// Talk over standard input and output: the default and only transport (accepted because
    /// many editors pass it).
    #[arg(long)]
    pub stdio: bool,
}

/// Runs the server on standard input and output until the editor shuts it down.
pub fn run(_args: &LspArgs) -> i32 {
    let (connection, io_threads) = Connection::stdio();
    let served = serve(&connection);
    drop(connection);
    let joined = io_threads.join();
    match (served, joined) {
        (Ok(()), Ok(())) => EXIT_OK,
        (Err(error), _) => {
            errln!("error: the language server stopped: {error}");
            EXIT_BAD_INPUT
        }
        (_, Err(error)) => {
            errln!("error: the language server stopped: {error}");
            EXIT_BAD_INPUT
        }
    }
}

/// What the server can do, as told to the editor.
fn capabilities() -> ServerCapabilities {
    ServerCapabilities {
        // Saves matter to the preview only: a saved file is rendered from disk again.
        text_document_sync: Some(TextDocumentSyncCapability::Options(TextDocumentSyncOptions {
            open_close: Some(true),
            change: Some(TextDocumentSyncKind::INCREMENTAL),
            save: Some(TextDocumentSyncSaveOptions::Supported(true)),
            ..TextDocumentSyncOptions::default()
        })),
        completion_provider: Some(CompletionOptions {
            trigger_characters: Some(vec!["\"".into(), "/".into(), "(".into(), ",".into(), ":".into()]),
            ..CompletionOptions::default()
        }),
        hover_provider: Some(HoverProviderCapability::Simple(true)),
        definition_provider: Some(OneOf::Left(true)),
        document_symbol_provider: Some(OneOf::Left(true)),
        ..ServerCapabilities::default()
    }
}

/// The handshake, then the message loop until `shutdown` and `exit`.
pub fn serve(connection: &Connection) -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let initialize = serde_json::json!({
        "capabilities": capabilities(),
        "serverInfo": ServerInfo {
            name: "lampshade".to_owned(),
            version: Some(env!("CARGO_PKG_VERSION").to_owned()),
        },
    });
    let (id, params) = connection.initialize_start()?;
    // The client's capabilities change nothing yet; a malformed `initialize` is still answered.
    let _client: Option<InitializeParams> = serde_json::from_value(params).ok();
    connection.initialize_finish(id, initialize)?;

    let sender = connection.sender.clone();
    let outbox: diagnostics::Outbox = Arc::new(move |message| {
        // Fails only once the writer has stopped, when the editor is gone.
        let _ = sender.send(message);
    });
    let publisher = Publisher::new(outbox);
    let mut server = Server {
        documents: Documents::default(),
        checker: Checker::start(publisher.clone(), LoadOptions::default()),
        publisher,
        preview: PreviewLink::start(),
    };

    for message in &connection.receiver {
        match message {
            Message::Request(request) => {
                if connection.handle_shutdown(&request)? {
                    return Ok(());
                }
                let response = server.answer(request);
                connection.sender.send(Message::Response(response))?;
            }
            Message::Notification(notification) => server.notified(notification),
            Message::Response(_) => {}
        }
    }
    Ok(())
}

struct Server {
    documents: Documents,
    publisher: Publisher,
    checker: Checker,
    /// Sends unsaved scene text to a `watch --serve` of the same scene.
    preview: PreviewLink,
}

impl Server {
    fn answer(&mut self, request: Request) -> Response {
        let id = request.id.clone();
        let answered = catch_unwind(AssertUnwindSafe(|| self.dispatch(request)));
        answered.unwrap_or_else(|_| {
            Response::new_err(
                id,
                ErrorCode::InternalError as i32,
                "internal error in lampshade (a bug); the server goes on".to_owned(),
            )
        })
    }

    fn dispatch(&mut self, request: Request) -> Response {
        let Request { id, method, params } = request;
        match method.as_str() {
            Completion::METHOD => respond::<CompletionParams, _>(id, params, |p| {
                let at = p.text_document_position;
                self.at_position(&at, completion::complete)
                    .map(CompletionResponse::Array)
            }),
            HoverRequest::METHOD => respond::<HoverParams, _>(id, params, |p| {
                let at = p.text_document_position_params;
                let meshes = &self.checker.meshes;
                self.at_position(&at, |document, offset| hover::hover(document, offset, meshes))
                    .flatten()
            }),
            GotoDefinition::METHOD => respond::<GotoDefinitionParams, _>(id, params, |p| {
                let at = p.text_document_position_params;
                self.at_position(&at, navigation::definition)
                    .flatten()
                    .map(GotoDefinitionResponse::Scalar)
            }),
            DocumentSymbolRequest::METHOD => respond::<DocumentSymbolParams, _>(id, params, |p| {
                self.documents
                    .get(&p.text_document.uri)
                    .map(|document| DocumentSymbolResponse::Nested(navigation::symbols(document)))
            }),
            _ => Response::new_err(
                id,
                ErrorCode::MethodNotFound as i32,
                format!("unknown request `{method}`"),
            ),
        }
    }

    /// `answer` for the open document and byte offset `at` names; `None` for a document that
    /// is not open.
    fn at_position<T>(
        &self,
        at: &TextDocumentPositionParams,
        answer: impl FnOnce(&documents::Document, usize) -> T,
    ) -> Option<T> {
        let document = self.documents.get(&at.text_document.uri)?;
        let offset = offset_of(&document.text, at.position);
        Some(answer(document, offset))
    }

    fn notified(&mut self, notification: Notification) {
        match notification.method.as_str() {
            DidOpenTextDocument::METHOD => {
                if let Ok(p) = serde_json::from_value::<DidOpenTextDocumentParams>(notification.params) {
                    let document = p.text_document;
                    self.documents
                        .open(document.uri.clone(), document.text, document.version);
                    self.changed(&document.uri);
                }
            }
            DidChangeTextDocument::METHOD => {
                if let Ok(p) = serde_json::from_value::<DidChangeTextDocumentParams>(notification.params)
                    && let Some(document) = self.documents.get_mut(&p.text_document.uri)
                {
                    document.apply(p.content_changes, p.text_document.version);
                    self.changed(&p.text_document.uri);
                }
            }
            DidCloseTextDocument::METHOD => {
                if let Ok(p) = serde_json::from_value::<DidCloseTextDocumentParams>(notification.params) {
                    if let Some(document) = self.documents.get(&p.text_document.uri) {
                        self.preview.file_wins(document.path.clone());
                    }
                    self.documents.close(&p.text_document.uri);
                    self.publisher.clear(&p.text_document.uri);
                }
            }
            DidSaveTextDocument::METHOD => {
                if let Ok(p) = serde_json::from_value::<DidSaveTextDocumentParams>(notification.params)
                    && let Some(document) = self.documents.get(&p.text_document.uri)
                {
                    self.preview.file_wins(document.path.clone());
                }
            }
            // `exit` without `shutdown`, settings: nothing to do.
            _ => {}
        }
    }

    /// The document at `uri` has new text: its syntax now, the rest on the checker.
    fn changed(&mut self, uri: &Url) {
        let Some(document) = self.documents.get_mut(uri) else {
            return;
        };
        self.publisher.saw(uri, document.version);
        if is_library(&document.text) {
            // A library on its own: everything but how scenes use it, on the unsaved text. Its
            // includes are small files, so this runs on the request thread.
            let diagnostics = match check_library_text(&document.path, &document.text) {
                Ok(()) => HashMap::new(),
                Err(error) => to_lsp(&error),
            };
            self.publisher.publish(uri, document.version, diagnostics);
            return;
        }
        self.preview.text(document.path.clone(), document.text.clone());
        self.publisher.saw(uri, document.version);
        match parse_scene_text(&document.path, &document.text) {
            Err(error) => self.publisher.publish(uri, document.version, to_lsp(&error)),
            Ok(()) => {
                document.parsed_text = Some(document.text.clone());
                self.checker.check(
                    uri.clone(),
                    document.path.clone(),
                    document.version,
                    document.text.clone(),
                );
            }
        }
    }
}

/// Whether `text` is a material library (`Materials(...)`) rather than a scene.
fn is_library(text: &str) -> bool {
    let code = text
        .lines()
        .map(str::trim_start)
        .find(|line| !line.is_empty() && !line.starts_with("//"))
        .unwrap_or("");
    code.starts_with("Materials")
}

/// Answers a request whose parameters are `P`: `InvalidParams` when they do not parse,
/// otherwise `handle`'s result (`null` for `None`).
fn respond<P: DeserializeOwned, R: Serialize>(
    id: RequestId,
    params: serde_json::Value,
    handle: impl FnOnce(P) -> Option<R>,
) -> Response {
    match serde_json::from_value::<P>(params) {
        Ok(params) => Response::new_ok(id, handle(params)),
        Err(error) => Response::new_err(id, ErrorCode::InvalidParams as i32, error.to_string()),
    }
}
