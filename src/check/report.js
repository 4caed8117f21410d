// The filters of a `lampshade check --report` page: a checkbox per verdict and a text filter on
// the scene's path hide rows of the summary table and the matching failure sections.
"use strict";

(() => {
  const form = document.getElementById("filters");
  if (!form) return;
  const boxes = [...form.querySelectorAll("input[type=checkbox]")];
  const name = document.getElementById("name-filter");
  const shown = document.getElementById("shown");
  const rows = [...document.querySelectorAll("#scenes tbody tr")];
  const sections = [...document.querySelectorAll("section.scene")];
  const apply = () => {
    const verdicts = new Set(boxes.filter((box) => box.checked).map((box) => box.value));
    const needle = name.value.trim().toLowerCase();
    const wanted = (node) =>
      verdicts.has(node.dataset.verdict) && node.dataset.name.toLowerCase().includes(needle);
    let count = 0;
    for (const row of rows) {
      row.hidden = !wanted(row);
      if (!row.hidden) count += 1;
    }
    for (const section of sections) section.hidden = !wanted(section);
    shown.textContent = `${count} of ${rows.length} scenes shown`;
  };
  for (const box of boxes) box.addEventListener("change", apply);
  name.addEventListener("input", apply);
  apply();
})();
