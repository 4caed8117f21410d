// The preview's pixel inspector: click a pixel of the image (or hover with Alt/Option held) to
// see what the frame drew there (GET /api/pick, schema in docs/pick.md): the object and the
// file, line and column it is written at (links open the editor, `watch --editor`), its
// material, normals and texels, and the lighting per light and term, summing to the pixel's
// colour. Every pixel of the same object is highlighted (GET /api/object-mask). Escape closes.
"use strict";
(() => {
  const view = document.getElementById("view");
  const stage = document.getElementById("stage");

  const style = document.createElement("style");
  style.textContent = `
    #view { cursor: crosshair; }
    #pick-mask { position: absolute; top: 0; left: 0; pointer-events: none; image-rendering: pixelated; }
    #pick-mask[hidden], #pick-marker[hidden], #pick-panel[hidden] { display: none; }
    #pick-marker { position: absolute; width: 9px; height: 9px; margin: -5px 0 0 -5px; pointer-events: none;
      border: 1px solid #fff; outline: 1px solid #000; }
    /* Beside the image when the window is wide enough, below it otherwise: never over it. As
       wide as its lighting table where the window allows, scrolling inside where it does not. */
    #pick-panel { display: inline-block; vertical-align: top; margin: 12px 12px 12px 0;
      width: max-content; max-width: min(820px, calc(100vw - 24px)); box-sizing: border-box; padding: 10px 12px;
      max-height: calc(100vh - 24px); overflow: auto;
      background: #252526; color: #ddd; border: 1px solid #444; border-radius: 4px;
      font: 12px/1.4 system-ui, sans-serif; }
    #pick-panel h2 { margin: 0 0 6px; font-size: 14px; }
    #pick-panel h3 { margin: 10px 0 4px; font-size: 12px; color: #9cdcfe; }
    #pick-panel table { border-collapse: collapse; width: 100%; font-variant-numeric: tabular-nums; }
    #pick-panel td, #pick-panel th { padding: 1px 4px; text-align: right; white-space: nowrap; }
    #pick-panel td:first-child, #pick-panel th:first-child { text-align: left; }
    #pick-panel tr.sum td { border-top: 1px solid #666; font-weight: 600; }
    #pick-panel tr.dark td { color: #888; }
    #pick-panel a { color: #4fc1ff; }
    #pick-panel .swatch { display: inline-block; width: 10px; height: 10px; border: 1px solid #888;
      vertical-align: middle; margin-right: 4px; }
    #pick-panel dl { display: grid; grid-template-columns: max-content 1fr; gap: 1px 8px; margin: 0; }
    #pick-panel dt { color: #aaa; }
    #pick-panel dd { margin: 0; overflow-wrap: anywhere; }
    #pick-panel p.pixel-sum { margin: 4px 0 0; color: #bbb; }
    #pick-panel .close { float: right; cursor: pointer; background: none; border: 0; color: #aaa; font-size: 16px; }
  `;
  document.head.appendChild(style);

  const mask = document.createElement("img");
  mask.id = "pick-mask";
  mask.hidden = true;
  mask.alt = "";
  stage.appendChild(mask);
  const marker = document.createElement("div");
  marker.id = "pick-marker";
  marker.hidden = true;
  stage.appendChild(marker);
  const panel = document.createElement("aside");
  panel.id = "pick-panel";
  panel.hidden = true;
  document.body.appendChild(panel);

  let picked = null; // {x, y} of the pixel shown in the panel
  let asked = 0; // the newest request, so that a late answer to an older one is dropped

  function imagePixel(event) {
    const box = view.getBoundingClientRect();
    const x = Math.floor((event.clientX - box.left) * view.naturalWidth / box.width);
    const y = Math.floor((event.clientY - box.top) * view.naturalHeight / box.height);
    if (x < 0 || y < 0 || x >= view.naturalWidth || y >= view.naturalHeight) return null;
    return { x, y };
  }

  async function pick(pixel) {
    const request = ++asked;
    picked = pixel;
    document.body.dataset.pick = "pending";
    let answer;
    try {
      const response = await fetch(`/api/pick?x=${pixel.x}&y=${pixel.y}`, { cache: "no-store" });
      answer = await response.json();
    } catch (error) {
      answer = { error: String(error) };
    }
    if (request !== asked) return;
    show(answer);
  }

  function number(value, digits = 4) {
    if (value === null || value === undefined) return "–";
    if (value === 0) return "0";
    const magnitude = Math.abs(value);
    return magnitude >= 1e4 || magnitude < 1e-3 ? value.toExponential(2) : Number(value.toPrecision(digits)).toString();
  }
  const triple = (v) => v ? `(${v.map((c) => number(c)).join(", ")})` : "–";
  const swatch = (v) => {
    const channel = (c) => Math.round(Math.min(Math.max(c, 0), 1) * 255);
    return `<span class="swatch" style="background: rgb(${v.map(channel).join(",")})"></span>`;
  };
  const escape = (text) => String(text).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" }[c]));

  // An editor link for a source location, from the template `watch --editor` gave.
  function sourceLink(at, label) {
    if (!at) return escape(label ?? "–");
    const template = document.body.dataset.editor || "vscode://file{path}:{line}:{column}";
    // Absolute, so it starts with "/"; each segment URL-encoded (spaces, "#", "?").
    const path = at.path.split("/").map(encodeURIComponent).join("/");
    const href = template.replaceAll("{path}", path).replaceAll("{line}", at.line).replaceAll("{column}", at.column);
    const name = at.path.split("/").pop();
    return `<a class="source-link" href="${escape(href)}" title="${escape(at.path)}">${escape(label ?? "")}${label ? " " : ""}${escape(name)}:${at.line}:${at.column}</a>`;
  }

  function lightingTable(point) {
    const rows = [];
    const row = (cells, cls = "") => rows.push(`<tr class="${cls}">${cells.map((c) => `<td>${c}</td>`).join("")}</tr>`);
    rows.push("<tr><th>term</th><th>N·L</th><th>att</th><th>spot</th><th>shadow</th><th>diffuse</th><th>specular</th></tr>");
    row(["emission", "", "", "", "", triple(point.emission), ""]);
    row(["ambient", "", "", "", "", triple(point.ambient), ""]);
    for (const light of point.lights) {
      const name = sourceLink(light.defined_at, `light ${light.index} (${light.kind})`);
      row([name, number(light.n_dot_l), number(light.attenuation), number(light.spot), number(light.shadow),
        triple(light.diffuse), triple(light.specular)], light.reaches ? "" : "dark");
    }
    row(["sum of the lights", "", "", "", "", triple(point.diffuse), triple(point.specular)], "sum");
    row(["+ ambient | + emission", "", "", "", "", triple(point.shown_ambient_diffuse), triple(point.shown_specular_emission)], "shown");
    // The two columns of the last row add up to the colour, which is clamped only when drawn.
    const total = `<p class="pixel-sum">pixel = the two columns' sum = ${triple(point.color)} before clamping `
      + `→ ${swatch(point.color)} clamped to [0, 1]</p>`;
    return `<table class="lighting">${rows.join("")}</table>${total}`;
  }

  function show(answer) {
    panel.hidden = false;
    marker.hidden = false;
    const box = view.getBoundingClientRect();
    marker.style.left = `${(picked.x + 0.5) * box.width / view.naturalWidth}px`;
    marker.style.top = `${(picked.y + 0.5) * box.height / view.naturalHeight}px`;
    const close = '<button class="close" title="close (Esc)">×</button>';
    if (answer.error) {
      panel.innerHTML = `${close}<h2>pixel ${picked.x}, ${picked.y}</h2><p>${escape(answer.error)}</p>`;
      document.body.dataset.pick = "error";
      hideMask();
      return;
    }
    const color = answer.color;
    const parts = [`${close}<h2>pixel ${answer.x}, ${answer.y} ${swatch(color.linear)}</h2>`];
    parts.push(`<dl><dt>colour</dt><dd>linear ${triple(color.linear)} → ${color.encoding} 8-bit (${color.rgb8.join(", ")})</dd>`);
    if (answer.debug_view) parts.push(`<dt>view</dt><dd>${escape(answer.debug_view)}</dd>`);
    if (answer.samples > 1) parts.push(`<dt>samples</dt><dd>${answer.samples}, ${answer.background_samples} background</dd>`);
    parts.push("</dl>");
    if (answer.background) {
      parts.push(`<p class="background">background ${triple(answer.background_color)}: no object covers this pixel.</p>`);
      panel.dataset.object = "";
      hideMask();
    }
    answer.surfaces.forEach((surface, index) => {
      const object = surface.object;
      const title = `“${escape(object.name)}” (object ${object.index})`;
      parts.push(`<h3 class="object">${title} ${sourceLink(object.defined_at)}${answer.surfaces.length > 1 ? ` · ${surface.samples} samples` : ""}</h3>`);
      const material = surface.material;
      const materialName = material.name ? `“${escape(material.name)}” ` : "";
      parts.push("<dl>");
      parts.push(`<dt>mesh</dt><dd>${sourceLink(surface.mesh.defined_at, surface.mesh.source ?? "")} · triangle ${surface.mesh.triangle} (vertices ${surface.mesh.vertices.join(", ")}) · barycentrics ${triple(surface.mesh.barycentrics)}</dd>`);
      parts.push(`<dt>material</dt><dd>${materialName}${material.origin}${material.defined_at ? " " + sourceLink(material.defined_at) : ""}${material.mesh_material !== null ? ` #${material.mesh_material}` : ""}</dd>`);
      parts.push(`<dt>k_a k_d k_s</dt><dd>${triple(material.ambient)} ${triple(material.diffuse)} ${triple(material.specular)} n=${number(material.shininess)}</dd>`);
      parts.push(`<dt>shading</dt><dd>${surface.shading} · ${escape(surface.lighting_model)} · ${surface.component}${surface.back_facing ? " · back face" : ""}</dd>`);
      parts.push(`<dt>position</dt><dd>${triple(surface.position)} · depth ${number(surface.depth, 6)} · distance ${number(surface.view_distance)}</dd>`);
      parts.push(`<dt>normal</dt><dd>${triple(surface.normal)} (face ${triple(surface.geometric_normal)})</dd>`);
      for (const texel of surface.texels) {
        const file = texel.file
          ? `<span class="texture-file" title="${escape(texel.file)}">${escape(texel.file.split("/").pop())}</span>`
          : `<span class="texture-file">texture #${texel.texture} of the mesh</span>`;
        const bias = texel.mip_bias ? ` ${texel.mip_bias > 0 ? "+" : "−"} bias ${number(Math.abs(texel.mip_bias))}` : "";
        const blend = texel.level_fraction > 0 ? `, ${number(texel.level_fraction, 2)} of the way to ${texel.level + 1}` : "";
        parts.push(`<dt>${texel.role} texture</dt><dd class="texel">${file} · uv ${triple(texel.uv)} · level ${texel.level}${blend} (lod ${number(texel.level_of_detail)}${bias}, ${texel.level_size.join("×")}) · texel ${triple(texel.texel)} = ${triple(texel.value)}</dd>`);
      }
      parts.push(`<dt>colour</dt><dd>${swatch(surface.color)}${triple(surface.color)}</dd></dl>`);
      const lighting = surface.lighting;
      const where = { pixel: "lit at this pixel", centroid: "lit once at the triangle's centroid (flat)",
        object: "lit once for the object (constant)", vertices: "lit at each vertex, interpolated (Gouraud)",
        none: "a debug view: no lighting" }[lighting.at];
      parts.push(`<p>${where}</p>`);
      lighting.points.forEach((point, k) => {
        if (lighting.points.length > 1) parts.push(`<h3>vertex ${surface.mesh.vertices[k]}</h3>`);
        parts.push(lightingTable(point));
      });
      if (index === 0) {
        panel.dataset.object = object.index;
        showMask(object.index);
      }
    });
    panel.innerHTML = parts.join("");
    document.body.dataset.pick = "shown";
  }

  function showMask(object) {
    const url = `/api/object-mask?object=${object}&v=${encodeURIComponent(document.body.dataset.image || "")}`;
    const next = new Image();
    next.onload = () => {
      mask.src = url;
      mask.style.width = `${view.getBoundingClientRect().width}px`;
      mask.hidden = false;
      document.body.dataset.highlight = object;
    };
    next.src = url;
  }

  function hideMask() {
    mask.hidden = true;
    delete document.body.dataset.highlight;
  }

  function closePanel() {
    asked++;
    picked = null;
    panel.hidden = true;
    marker.hidden = true;
    hideMask();
    delete document.body.dataset.pick;
  }

  view.addEventListener("click", (event) => {
    const pixel = imagePixel(event);
    if (pixel) pick(pixel);
  });
  let lastHover = "";
  view.addEventListener("mousemove", (event) => {
    if (!event.altKey) return;
    const pixel = imagePixel(event);
    if (!pixel || `${pixel.x},${pixel.y}` === lastHover) return;
    lastHover = `${pixel.x},${pixel.y}`;
    pick(pixel);
  });
  panel.addEventListener("click", (event) => {
    if (event.target.classList.contains("close")) closePanel();
  });
  document.addEventListener("keydown", (event) => {
    if (event.key === "Escape") closePanel();
  });
  // A new image: what the pixel shows may have changed, so ask again.
  new MutationObserver(() => {
    if (picked) pick(picked);
  }).observe(document.body, { attributes: true, attributeFilter: ["data-image"] });
})();
