// Compare views for two images: side by side, swipe (a draggable divider: the base image left of
// it, the current one right), onion skin (the current image over the base at an opacity) and
// difference (|current − base| per channel, amplified ×1, ×4 or ×16). Shared, as one file, by
// the preview of `lampshade watch --serve` (served as /page/compare.js: the new image against
// the previous one or a pinned one) and by the `lampshade check --report` page (inlined: actual
// against expected). Everything is drawn client-side into a canvas from decoded images, so the
// pixels shown are the images' own (no smoothing: `image-rendering: pixelated`).
//
// Markup it recognises, on load:
// - the preview: `#stage` holding `<img id="view">`; the compare bar goes above the stage, with
//   a pin button and a turntable button (which plays the watch's `/turntable.png` below it);
// - a report: every `[data-compare]` element holding `<img data-role="expected">` and
//   `<img data-role="actual">`, and optionally more `<img data-role="layer" data-name="…">`
//   (the heat map, FLIP's error map), each shown alone as a mode of its own; small images are
//   enlarged (pixelated) there.
// The chosen mode, divider, opacity and gain are remembered in localStorage.
"use strict";

(() => {
  const STYLE = `
    .compare-bar { display: flex; flex-wrap: wrap; gap: 4px 10px; align-items: center;
      font: 13px system-ui, sans-serif; margin: 6px 0; }
    .compare-bar .modes { display: inline-flex; }
    .compare-bar button { font: inherit; padding: 2px 9px; border: 1px solid #777;
      background: #3a3a3a; color: #eee; cursor: pointer; }
    .compare-bar .modes button { border-radius: 0; margin-left: -1px; }
    .compare-bar .modes button:first-child { border-radius: 3px 0 0 3px; margin-left: 0; }
    .compare-bar .modes button:last-child { border-radius: 0 3px 3px 0; }
    .compare-bar button[aria-pressed="true"] { background: #4a7bd0; border-color: #4a7bd0; color: #fff; }
    .compare-bar label[hidden], .compare-bar span[hidden] { display: none; }
    .compare-bar input[type=range] { width: 110px; vertical-align: middle; }
    .compare-frame { position: relative; display: inline-block; line-height: 0; }
    .compare-frame[hidden] { display: none; }
    .compare-frame canvas { display: block; max-width: 100%; image-rendering: pixelated;
      touch-action: none; }
    .compare-frame.swipe canvas { cursor: ew-resize; }
    .compare-divider { position: absolute; top: 0; bottom: 0; width: 0;
      border-left: 1px solid #fff; box-shadow: 0 0 0 1px rgba(0,0,0,.6); pointer-events: none; }
    .compare-divider[hidden] { display: none; }
    .compare-note { color: #aaa; }
    #compare-bar { margin: 8px 12px 0; }
    #turntable { display: block; margin: 0 12px 12px; max-width: calc(100vw - 24px); }
    #turntable[hidden] { display: none; }
  `;

  const MODE_NAMES = {
    plain: "image", side: "side by side", swipe: "swipe", onion: "onion skin", difference: "difference",
  };
  const GAINS = [1, 4, 16];
  const GAP = 8; // pixels between the two images side by side

  function injectStyle() {
    if (document.getElementById("compare-style")) return;
    const style = document.createElement("style");
    style.id = "compare-style";
    style.textContent = STYLE;
    document.head.appendChild(style);
  }

  function load(key, fallback) {
    try {
      const saved = JSON.parse(localStorage.getItem(key) ?? "null");
      return saved && typeof saved === "object" ? { ...fallback, ...saved } : { ...fallback };
    } catch (_) {
      return { ...fallback }; // storage refused (a private window, a file:// policy)
    }
  }

  function save(key, settings) {
    try { localStorage.setItem(key, JSON.stringify(settings)); } catch (_) { /* not kept */ }
  }

  function element(tag, attributes = {}, text = "") {
    const node = document.createElement(tag);
    for (const [name, value] of Object.entries(attributes)) node.setAttribute(name, value);
    if (text) node.textContent = text;
    return node;
  }

  // An image source's pixels, read through a canvas of its own size.
  function pixelsOf(source) {
    const { width, height } = sizeOf(source);
    const canvas = element("canvas");
    canvas.width = width;
    canvas.height = height;
    const context = canvas.getContext("2d");
    context.drawImage(source, 0, 0);
    return context.getImageData(0, 0, width, height);
  }

  function sizeOf(source) {
    return source instanceof HTMLImageElement
      ? { width: source.naturalWidth, height: source.naturalHeight }
      : { width: source.width, height: source.height };
  }

  // |current − base| per channel times `gain`, clamped; opaque. Where the sizes differ, the
  // part outside the base counts as black.
  function differenceImage(base, current, gain) {
    const a = pixelsOf(base);
    const b = pixelsOf(current);
    const out = new ImageData(b.width, b.height);
    for (let y = 0; y < b.height; y++) {
      for (let x = 0; x < b.width; x++) {
        const i = (y * b.width + x) * 4;
        const inBase = x < a.width && y < a.height;
        const j = (y * a.width + x) * 4;
        for (let c = 0; c < 3; c++) {
          const expected = inBase ? a.data[j + c] : 0;
          out.data[i + c] = Math.min(255, Math.abs(b.data[i + c] - expected) * gain);
        }
        out.data[i + 3] = 255;
      }
    }
    return out;
  }

  // One viewer: a bar of modes and a canvas. `modes` lists the compare modes offered (keys of
  // MODE_NAMES), `layers` extra single images by name; `storageKey` remembers the settings.
  class CompareView {
    constructor({ modes, layers = [], storageKey, defaultMode, zoomTo = 0 }) {
      this.modes = modes;
      this.zoomTo = zoomTo; // small images are shown enlarged to about this many CSS pixels
      this.layers = layers; // [{ name, image }]
      this.storageKey = storageKey;
      this.settings = load(storageKey, { mode: defaultMode, split: 0.5, opacity: 0.5, gain: 4 });
      if (!this.allModes().includes(this.settings.mode)) this.settings.mode = defaultMode;
      this.base = null;
      this.current = null;
      this.bar = element("div", { class: "compare-bar" });
      this.frame = element("div", { class: "compare-frame" });
      this.canvas = element("canvas");
      this.canvas.width = 0; // nothing drawn yet
      this.divider = element("div", { class: "compare-divider", hidden: "" });
      this.frame.append(this.canvas, this.divider);
      this.buildBar();
      this.listenForDrags();
    }

    allModes() {
      return [...this.modes, ...this.layers.map((layer) => "layer:" + layer.name)];
    }

    buildBar() {
      const modes = element("span", { class: "modes", role: "group", "aria-label": "compare mode" });
      this.modeButtons = this.allModes().map((mode) => {
        const name = mode.startsWith("layer:") ? mode.slice(6) : MODE_NAMES[mode];
        const button = element("button", { type: "button", "data-mode": mode }, name);
        button.addEventListener("click", () => this.setMode(mode));
        modes.appendChild(button);
        return button;
      });
      this.bar.appendChild(modes);

      this.splitControl = element("label", { class: "split" }, "divider ");
      this.splitInput = element("input", { type: "range", min: "0", max: "1", step: "0.001" });
      this.splitInput.addEventListener("input", () => this.change({ split: Number(this.splitInput.value) }));
      this.splitControl.appendChild(this.splitInput);

      this.opacityControl = element("label", { class: "opacity" }, "opacity ");
      this.opacityInput = element("input", { type: "range", min: "0", max: "1", step: "0.01" });
      this.opacityInput.addEventListener("input", () => this.change({ opacity: Number(this.opacityInput.value) }));
      this.opacityControl.appendChild(this.opacityInput);

      this.gainControl = element("label", { class: "gain" }, "amplified ");
      this.gainInput = element("select");
      for (const gain of GAINS) this.gainInput.appendChild(element("option", { value: String(gain) }, "×" + gain));
      this.gainInput.addEventListener("change", () => this.change({ gain: Number(this.gainInput.value) }));
      this.gainControl.appendChild(this.gainInput);

      this.note = element("span", { class: "compare-note" });
      this.bar.append(this.splitControl, this.opacityControl, this.gainControl, this.note);
    }

    // Dragging on the canvas moves the divider (pointer capture keeps the drag past its edge).
    listenForDrags() {
      const follow = (event) => {
        const box = this.canvas.getBoundingClientRect();
        if (box.width === 0) return;
        const split = Math.min(1, Math.max(0, (event.clientX - box.left) / box.width));
        this.change({ split });
      };
      this.canvas.addEventListener("pointerdown", (event) => {
        if (this.settings.mode !== "swipe") return;
        this.canvas.setPointerCapture(event.pointerId);
        follow(event);
      });
      this.canvas.addEventListener("pointermove", (event) => {
        if (this.settings.mode === "swipe" && this.canvas.hasPointerCapture(event.pointerId)) follow(event);
      });
    }

    change(settings) {
      Object.assign(this.settings, settings);
      save(this.storageKey, this.settings);
      this.draw();
    }

    setMode(mode) {
      if (this.allModes().includes(mode)) this.change({ mode });
    }

    // The pair to compare: `base` (previous, pinned or expected) and `current` (new or actual),
    // each an <img> that has loaded or a canvas; `base` may be null (nothing to compare yet).
    setImages(base, current) {
      this.base = base;
      this.current = current;
      this.draw();
    }

    setNote(text) {
      this.note.textContent = text;
    }

    draw() {
      const { mode, split, opacity, gain } = this.settings;
      for (const button of this.modeButtons) {
        button.setAttribute("aria-pressed", String(button.dataset.mode === mode));
      }
      this.splitControl.hidden = mode !== "swipe";
      this.opacityControl.hidden = mode !== "onion";
      this.gainControl.hidden = mode !== "difference";
      this.splitInput.value = String(split);
      this.opacityInput.value = String(opacity);
      this.gainInput.value = String(gain);
      this.frame.classList.toggle("swipe", mode === "swipe");
      this.frame.dataset.mode = mode;
      this.divider.hidden = true;
      const current = this.current;
      if (current === null) return;
      const base = this.base ?? current; // nothing to compare against yet: the image itself
      const { width, height } = sizeOf(current);
      const canvas = this.canvas;
      const layer = this.layers.find((candidate) => "layer:" + candidate.name === mode);
      const shown = layer ? sizeOf(layer.image) : { width: mode === "side" ? 2 * width + GAP : width, height };
      if (canvas.width !== shown.width || canvas.height !== shown.height) {
        canvas.width = shown.width;
        canvas.height = shown.height;
      }
      const zoom = Math.max(1, Math.floor(this.zoomTo / Math.max(shown.width, shown.height)));
      canvas.style.width = this.zoomTo ? shown.width * zoom + "px" : "";
      const context = canvas.getContext("2d");
      context.imageSmoothingEnabled = false;
      context.globalAlpha = 1;
      context.clearRect(0, 0, canvas.width, canvas.height);
      if (layer) {
        context.drawImage(layer.image, 0, 0);
      } else if (mode === "side") {
        context.drawImage(base, 0, 0);
        context.drawImage(current, width + GAP, 0);
      } else if (mode === "swipe") {
        const at = Math.round(split * width);
        context.drawImage(current, 0, 0);
        context.save();
        context.beginPath();
        context.rect(0, 0, at, height);
        context.clip();
        context.drawImage(base, 0, 0);
        context.restore();
        this.divider.hidden = false;
        this.divider.style.left = (100 * at / width) + "%";
      } else if (mode === "onion") {
        context.drawImage(base, 0, 0);
        context.globalAlpha = opacity;
        context.drawImage(current, 0, 0);
        context.globalAlpha = 1;
      } else if (mode === "difference") {
        context.putImageData(differenceImage(base, current, gain), 0, 0);
      } else {
        context.drawImage(current, 0, 0);
      }
    }
  }

  // A copy of what `image` shows now, kept when the <img> moves on to the next image (the
  // server keeps only the latest image, so an old URL would fetch the new one).
  function snapshot(image) {
    const copy = element("canvas");
    copy.width = image.naturalWidth;
    copy.height = image.naturalHeight;
    copy.getContext("2d").drawImage(image, 0, 0);
    return copy;
  }

  // The preview: each image `#view` loads becomes the current one, the one before it the base,
  // unless an image is pinned. The plain view stays the <img> itself (its contract is the
  // page's); the other modes show the canvas in its place.
  function attachToPreview(view) {
    const stage = document.getElementById("stage");
    const viewer = new CompareView({
      modes: ["plain", "side", "swipe", "onion", "difference"],
      storageKey: "lampshade-preview-compare",
      defaultMode: "plain",
    });
    viewer.frame.id = "compare";
    const pin = element("button", { type: "button", id: "pin", "aria-pressed": "false" }, "pin");
    pin.title = "keep the current image as the one every new image is compared with";
    viewer.bar.insertBefore(pin, viewer.note);
    viewer.bar.id = "compare-bar";
    stage.parentNode.insertBefore(viewer.bar, stage);
    stage.insertBefore(viewer.frame, view.nextSibling);

    // The scene turning about its up direction, at reduced size, made by the watch on request
    // (an APNG, which an <img> plays); the version makes each image's turntable a new request.
    const spin = element("button", { type: "button", id: "turntable-button", "aria-pressed": "false" }, "turntable");
    spin.title = "play the scene orbiting its target (36 frames at reduced size)";
    viewer.bar.insertBefore(spin, viewer.note);
    const player = element("img", { id: "turntable", alt: "the scene turning", hidden: "" });
    stage.parentNode.insertBefore(player, stage.nextSibling);
    spin.addEventListener("click", () => {
      const on = player.hidden;
      player.hidden = !on;
      spin.setAttribute("aria-pressed", String(on));
      if (on) player.src = "/turntable.png?frames=36&v=" + encodeURIComponent(document.body.dataset.image ?? "");
      else player.removeAttribute("src");
    });

    let previous = null;
    let current = null;
    let pinned = null;
    const show = () => {
      const base = pinned ?? previous;
      viewer.setImages(base, current);
      const plain = viewer.settings.mode === "plain";
      view.style.display = plain ? "" : "none";
      viewer.frame.hidden = plain;
      viewer.setNote(current === null ? "" : base === null
        ? "no earlier image yet"
        : pinned ? "against the pinned image" : "against the previous image");
      document.body.dataset.compare = viewer.settings.mode;
      document.body.dataset.compareBase = pinned ? "pinned" : previous ? "previous" : "none";
    };
    // Each image has its own URL (its version in the query). The same URL can be reported
    // twice: by the check below, when the image was complete before this script ran, and by
    // its load event if that was still queued; the second must not become its own "previous".
    let shownSource = null;
    const loaded = () => {
      if (!view.naturalWidth || view.src === shownSource) return;
      shownSource = view.src;
      previous = current;
      current = snapshot(view);
      show();
    };
    view.addEventListener("load", loaded);
    // This script may arrive after the first image did.
    if (view.complete && view.getAttribute("src")) loaded();
    pin.addEventListener("click", () => {
      pinned = pinned === null ? current : null;
      pin.setAttribute("aria-pressed", String(pinned !== null));
      pin.textContent = pinned === null ? "pin" : "unpin";
      show();
    });
    const change = viewer.change.bind(viewer);
    viewer.change = (settings) => { change(settings); show(); };
    if (current === null) show();
    window.lampshadeCompare = viewer;
  }

  // A report's failure: expected is the base, actual the current image; the heat map and FLIP
  // map are modes of their own. The <figure>s stay below as they are (links to full size).
  function attachToReport(holder, index) {
    const images = [...holder.querySelectorAll("img[data-role]")];
    const expected = images.find((image) => image.dataset.role === "expected");
    const actual = images.find((image) => image.dataset.role === "actual");
    if (!expected || !actual) return;
    const layers = images
      .filter((image) => image.dataset.role === "layer")
      .map((image) => ({ name: image.dataset.name, image }));
    const viewer = new CompareView({
      modes: ["side", "swipe", "onion", "difference"],
      layers,
      storageKey: "lampshade-report-compare",
      defaultMode: "side",
      zoomTo: 640,
    });
    viewer.frame.dataset.scene = String(index);
    holder.parentNode.insertBefore(viewer.bar, holder);
    holder.parentNode.insertBefore(viewer.frame, holder);
    holder.compareView = viewer;
    // A setting changed in one viewer applies to every viewer of the page.
    const change = viewer.change.bind(viewer);
    viewer.change = (settings) => {
      change(settings);
      for (const other of document.querySelectorAll("[data-compare]")) {
        const view = other.compareView;
        if (view && view !== viewer) {
          Object.assign(view.settings, settings);
          if (!view.allModes().includes(view.settings.mode)) view.settings.mode = "side";
          view.draw();
        }
      }
    };
    const ready = () => images.every((image) => image.complete && image.naturalWidth > 0);
    const start = () => { if (ready()) viewer.setImages(expected, actual); };
    for (const image of images) image.addEventListener("load", start);
    start();
  }

  function attach() {
    injectStyle();
    const view = document.getElementById("view");
    if (view && document.getElementById("stage")) attachToPreview(view);
    document.querySelectorAll("[data-compare]").forEach(attachToReport);
  }

  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", attach);
  else attach();
})();
