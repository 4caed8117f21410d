// The preview's view controls (see src/watch/view.rs): drag to orbit about the target,
// shift-drag or right-drag to pan, wheel to dolly; copy the camera as RON or write it into the
// scene file; the shading, lighting-model and debug-view overrides; reset.
//
// The page owns its camera and sends the whole view each time (POST /api/view), one request in
// flight: moves made meanwhile are merged into the next request, never queued. While moving the
// server answers with reduced frames; the request sent when the moves stop gets the full image.
// `window.lampshadeView` exposes the camera math and the frame timings (input event to the new
// image painted) for the tests and the benchmark.
"use strict";
(() => {
  const view = document.getElementById("view");
  const stage = document.getElementById("stage");

  // ----- camera math (plain arrays; the camera's `up` is kept, as a turntable does) -----
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const length = (a) => Math.sqrt(dot(a, a));
  const normalize = (a) => scale(a, 1 / length(a));
  // How close to the up axis an orbit may take the eye: the loader refuses a view along `up`.
  const POLE_MARGIN = 1e-3;

  // A unit vector perpendicular to `up` (any one), for a view that looks straight along it.
  function perpendicular(up) {
    const axis = Math.abs(up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
    return normalize(cross(up, axis));
  }

  // Turns the eye about the target: `yaw` radians about `up`, `pitch` radians towards it
  // (positive raises the eye), stopping short of the poles.
  function orbit(camera, yaw, pitch) {
    const up = normalize(camera.up);
    const offset = sub(camera.eye, camera.target);
    const radius = length(offset);
    const height = dot(offset, up);
    const across = sub(offset, scale(up, height));
    const e1 = length(across) > 1e-12 * radius ? normalize(across) : perpendicular(up);
    const e2 = cross(up, e1);
    const polar = Math.acos(Math.max(-1, Math.min(1, height / radius)));
    const newPolar = Math.max(POLE_MARGIN, Math.min(Math.PI - POLE_MARGIN, polar - pitch));
    const direction = add(
      scale(add(scale(e1, Math.cos(-yaw)), scale(e2, Math.sin(-yaw))), Math.sin(newPolar)),
      scale(up, Math.cos(newPolar)),
    );
    return { ...camera, eye: add(camera.target, scale(direction, radius)) };
  }

  // Moves eye and target together across the view: `dx`, `dy` in pixels of an image
  // `imageHeight` pixels high, so the point at the target follows the pointer.
  function pan(camera, dx, dy, imageHeight) {
    const forward = sub(camera.target, camera.eye);
    const distance = length(forward);
    const right = normalize(cross(forward, camera.up));
    const screenUp = normalize(cross(right, forward));
    const perPixel = (2 * distance * Math.tan((camera.fov * Math.PI) / 360)) / imageHeight;
    const shift = add(scale(right, -dx * perPixel), scale(screenUp, dy * perPixel));
    return { ...camera, eye: add(camera.eye, shift), target: add(camera.target, shift) };
  }

  // Moves the eye towards the target (`steps` > 0) or away from it, by a factor per step.
  function dolly(camera, steps) {
    const offset = sub(camera.eye, camera.target);
    const factor = Math.max(Math.exp(-steps * 0.1), 1e-6 / Math.max(length(offset), 1e-300));
    return { ...camera, eye: add(camera.target, scale(offset, factor)) };
  }

  // ----- the view and its requests -----
  let camera = null; // the camera shown or being moved, {eye, target, up, fov}
  let previewCamera = false; // whether the page sends its own camera
  let cameraRon = null; // the shown camera in the scene format, as the server wrote it
  let fullSize = null;
  const overrides = { shading: null, model: null, debug: null };
  let inFlight = false;
  let wanted = null; // the view to send once the request in flight is answered
  let firstUnsentInput = null; // when the oldest input not yet sent happened
  let dragging = null;
  let stillTimer = null;
  const frames = []; // {latency, at, moving, width}

  function request(moving) {
    return { camera: previewCamera ? camera : null, moving, ...overrides };
  }

  function send(moving) {
    wanted = request(moving);
    if (!inFlight) flush();
  }

  async function flush() {
    if (wanted === null) return;
    const body = wanted;
    const inputAt = firstUnsentInput;
    wanted = null;
    firstUnsentInput = null;
    inFlight = true;
    try {
      const sentAt = performance.now();
      const response = await fetch("/api/view", {
        method: "POST",
        headers: { "Content-Type": "application/json" },
        body: JSON.stringify(body),
      });
      const state = await response.json();
      // Answered: the next request goes out now (finally below) while this image is fetched
      // and decoded.
      if (state.image) paint(state, inputAt, { sentAt, answeredAt: performance.now() });
      else if (state.error) showProblem(state.error);
    } catch (error) {
      showProblem(String(error));
    } finally {
      inFlight = false;
      flush();
    }
  }

  // Swaps the image in once decoded, then notes when it was painted and where the time went:
  // `waited` from the input to the request (a request was in flight), `request` until the
  // answer (the server's `timings` of it: load, render, encode), `image` to fetch and decode
  // the PNG, and the rest until the next paint.
  async function paint(state, inputAt, sent = null) {
    const url = "/image.png?v=" + encodeURIComponent(state.image);
    const next = new Image();
    next.src = url;
    try {
      await next.decode();
    } catch {
      return;
    }
    const decodedAt = performance.now();
    if (typeof wantedImage !== "undefined") {
      if (wantedImage !== null && newer(wantedImage, state.image)) return;
      wantedImage = state.image;
    }
    view.src = url;
    document.body.dataset.image = state.image;
    adopt(state);
    requestAnimationFrame(() => {
      const at = performance.now();
      if (inputAt !== null) {
        frames.push({
          latency: at - inputAt,
          at,
          moving: state.view?.moving ?? false,
          width: next.naturalWidth,
          waited: sent ? sent.sentAt - inputAt : null,
          request: sent ? sent.answeredAt - sent.sentAt : null,
          image: sent ? decodedAt - sent.answeredAt : null,
          server: state.view?.timings ?? null,
        });
      }
    });
  }

  // Image versions are `<run>-<generation>`.
  function newer(a, b) {
    const generation = (version) => Number(String(version).split("-")[1] ?? 0);
    return generation(a) > generation(b);
  }

  // The state's view: its camera becomes the page's when the page is not moving its own.
  let lastState = null;
  function adopt(state) {
    lastState = state;
    const shown = state.view;
    if (!shown) return;
    fullSize = [shown.width, shown.height];
    view.style.width = shown.width + "px";
    const idle = dragging === null && !inFlight && wanted === null && stillTimer === null;
    if (idle && shown.camera) {
      camera = shown.camera;
      previewCamera = shown.preview_camera;
      cameraRon = shown.camera_ron;
    } else if (!previewCamera) {
      cameraRon = shown.camera_ron;
    } else if (shown.preview_camera && shown.camera) {
      cameraRon = shown.camera_ron;
    }
    for (const key of ["shading", "model", "debug"]) {
      if (idle) overrides[key] = shown[key];
      controls[key].value = overrides[key] ?? "";
    }
    controls.write.disabled = !previewCamera;
    controls.copy.disabled = cameraRon === null;
    controls.ron.textContent = cameraRon === null ? "" : "camera: " + cameraRon + ",";
    document.body.dataset.previewCamera = String(previewCamera);
  }

  function showProblem(message) {
    controls.note.textContent = message;
  }

  // ----- input -----
  function noteInput(event) {
    if (firstUnsentInput === null) firstUnsentInput = event.timeStamp;
  }

  view.addEventListener("contextmenu", (event) => event.preventDefault());
  view.addEventListener("dragstart", (event) => event.preventDefault());
  view.addEventListener("pointerdown", (event) => {
    if (camera === null) return;
    event.preventDefault();
    view.setPointerCapture(event.pointerId);
    const panning = event.button === 2 || event.shiftKey;
    dragging = { x: event.clientX, y: event.clientY, panning, moved: false };
  });
  view.addEventListener("pointermove", (event) => {
    if (dragging === null) return;
    const dx = event.clientX - dragging.x;
    const dy = event.clientY - dragging.y;
    if (dx === 0 && dy === 0) return;
    dragging.x = event.clientX;
    dragging.y = event.clientY;
    dragging.moved = true;
    noteInput(event);
    // Displayed pixels, converted to image pixels for the pan.
    const shownHeight = view.getBoundingClientRect().height || 1;
    const imageHeight = fullSize ? fullSize[1] : shownHeight;
    camera = dragging.panning
      ? pan(camera, dx * (imageHeight / shownHeight), dy * (imageHeight / shownHeight), imageHeight)
      : orbit(camera, dx * 0.01, dy * 0.01);
    previewCamera = true;
    send(true);
  });
  // A press and release without movement is a click, left to the pixel inspector; the click
  // that ends a drag is swallowed here (capture phase, before pick.js sees it), so an orbit does
  // not also open the inspector at the pixel where it stopped.
  let swallowNextClick = false;
  const endDrag = (event) => {
    if (dragging === null) return;
    const moved = dragging.moved;
    dragging = null;
    if (view.hasPointerCapture(event.pointerId)) view.releasePointerCapture(event.pointerId);
    if (!moved) return;
    swallowNextClick = event.type === "pointerup";
    send(false);
  };
  view.addEventListener("pointerup", endDrag);
  view.addEventListener("pointercancel", endDrag);
  view.addEventListener("pointerdown", () => (swallowNextClick = false), true);
  view.addEventListener(
    "click",
    (event) => {
      if (!swallowNextClick) return;
      swallowNextClick = false;
      event.stopImmediatePropagation();
    },
    true,
  );
  view.addEventListener(
    "wheel",
    (event) => {
      if (camera === null) return;
      event.preventDefault();
      noteInput(event);
      // A mouse wheel notch is about 100 pixels of delta: a tenth closer per notch.
      camera = dolly(camera, -event.deltaY / 100);
      previewCamera = true;
      send(true);
      clearTimeout(stillTimer);
      stillTimer = setTimeout(() => {
        stillTimer = null;
        send(false);
      }, 150);
    },
    { passive: false },
  );

  // ----- the toolbar -----
  const style = document.createElement("style");
  style.textContent = `
    #view-controls { display: flex; flex-wrap: wrap; gap: 6px 12px; align-items: center;
      padding: 6px 12px; background: #252525; font-size: 13px; }
    #view-controls button, #view-controls select { font: inherit; background: #333; color: #ddd;
      border: 1px solid #555; border-radius: 3px; padding: 2px 8px; }
    #view-controls button:disabled { color: #777; }
    #view-controls label { display: flex; gap: 4px; align-items: center; }
    #camera-ron { font: 12px ui-monospace, "DejaVu Sans Mono", monospace; color: #aaa;
      user-select: all; }
    #view-note { color: #ff9d9d; }
    #view { cursor: grab; touch-action: none; }
    #view:active { cursor: grabbing; }
  `;
  document.head.append(style);
  const bar = document.createElement("div");
  bar.id = "view-controls";
  const button = (id, label, title, action) => {
    const b = document.createElement("button");
    b.id = id;
    b.textContent = label;
    b.title = title;
    b.addEventListener("click", action);
    bar.append(b);
    return b;
  };
  const select = (id, label, choices, key) => {
    const wrapper = document.createElement("label");
    wrapper.textContent = label;
    const s = document.createElement("select");
    s.id = id;
    for (const [value, text] of choices) s.append(new Option(text, value));
    s.addEventListener("change", () => {
      overrides[key] = s.value === "" ? null : s.value;
      send(false);
    });
    wrapper.append(s);
    bar.append(wrapper);
    return s;
  };
  const controls = {};
  controls.reset = button("view-reset", "Reset view", "the file's camera and the scene's own shading", () => {
    previewCamera = false;
    for (const key of Object.keys(overrides)) overrides[key] = null;
    send(false);
  });
  controls.copy = button("view-copy", "Copy camera", "copy the camera as RON for the scene file", copyCamera);
  controls.write = button("view-write", "Write camera to file", "replace the scene file's camera with this one", writeCamera);
  controls.shading = select("view-shading", "shading", [["", "scene's"], ["constant", "constant"], ["flat", "flat"], ["gouraud", "gouraud"], ["phong", "phong"]], "shading");
  controls.model = select("view-model", "model", [["", "scene's"], ["phong", "Phong"], ["blinn-phong", "Blinn-Phong"], ["lambert", "Lambert"], ["cook-torrance", "Cook-Torrance"], ["unlit", "unlit"]], "model");
  controls.debug = select("view-debug", "debug", [["", "lit image"], ["ambient", "ambient"], ["diffuse", "diffuse"], ["specular", "specular"], ["normals", "normals"], ["depth", "depth"]], "debug");
  controls.ron = document.createElement("code");
  controls.ron.id = "camera-ron";
  controls.note = document.createElement("span");
  controls.note.id = "view-note";
  bar.append(controls.ron, controls.note);
  stage.before(bar);
  controls.copy.disabled = true;
  controls.write.disabled = true;

  let lastCopied = null;
  async function copyCamera() {
    if (cameraRon === null) return;
    const text = "camera: " + cameraRon + ",";
    lastCopied = text;
    try {
      await navigator.clipboard.writeText(text);
      controls.note.textContent = "";
    } catch {
      // Without clipboard access (an insecure context, a headless browser) the text stays
      // selectable in the toolbar.
      controls.note.textContent = "select the camera text to copy it";
    }
  }

  async function writeCamera() {
    if (!previewCamera || camera === null) return;
    const response = await fetch("/api/camera", {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify(camera),
    });
    const answer = await response.json();
    controls.note.textContent = answer.error ?? "";
  }

  // The states every build publishes (the page's own event stream, see preview.html), and the
  // current one, which the stream may have sent before this script ran.
  if (typeof events !== "undefined") {
    events.addEventListener("message", (message) => adopt(JSON.parse(message.data)));
  }
  fetch("/api/state")
    .then((response) => response.json())
    .then((state) => {
      if (lastState === null) adopt(state);
    });

  window.lampshadeView = {
    orbit,
    pan,
    dolly,
    frames,
    camera: () => camera,
    cameraRon: () => cameraRon,
    lastCopied: () => lastCopied,
    state: () => lastState,
    busy: () => dragging !== null || inFlight || wanted !== null || stillTimer !== null,
    // While a request of this page is in flight the images published are its answers, which
    // `paint` shows (preview.html leaves them alone).
    paintsItself: () => inFlight,
  };
})();
