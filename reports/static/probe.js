/* caustics-harness report: the pixel probe.
 *
 * Hovering any panel of a view (method, reference, difference, SSIM, FLIP, regions,
 * A/B) shows, for the pixel under the pointer, the method, reference and difference
 * values per channel and their luminance, in the view's units, and the reference's
 * standard error sqrt(Var[mean]) there and the z-score difference / standard error
 * (per channel, and of the luminance over the luminance's Σ w_c σ_c: the z-score map's
 * value), read from the view's float32 data
 * (view_data.js), so they are the EXR's values to within 0.05 % (the data's
 * rounding, reports/page_data.py). A square marks the pixel on every panel of the
 * view.
 *
 * The tooltip (div#probe) keeps the numbers in full in data attributes: data-view,
 * data-x and data-y (display pixel), data-exr ("x0 x1 y0 y1", EXR pixels) and one
 * row per layer with data-layer and data-values (JSON: each channel, then luminance).
 */
(function () {
  "use strict";

  const report = window.causticsReport;
  const ROWS = [
    ["method", "method"],
    ["reference", "reference"],
    ["difference", "difference"],
    ["reference_se", "ref. std. error"],
    ["z", "z = diff. / σ"],
  ];

  /* a / b, NaN where b is not positive (no standard error: z undefined). */
  function ratio(a, b) {
    return b > 0 ? a / b : NaN;
  }

  let tooltip = null;

  function tooltipElement() {
    if (!tooltip) {
      tooltip = document.createElement("div");
      tooltip.id = "probe";
      tooltip.hidden = true;
      tooltip.setAttribute("role", "status");
      document.body.appendChild(tooltip);
    }
    return tooltip;
  }

  /* Layer values at a display pixel: {name: [channels..., luminance] or null}. */
  function valuesAt(data, x, y) {
    const method = report.pixel(data, "method", x, y);
    const reference = report.pixel(data, "reference", x, y);
    const se = report.pixel(data, "reference_se", x, y);
    const difference = report.pixel(data, "difference", x, y);
    return {
      method: method.concat([report.luminance(method)]),
      reference: reference.concat([report.luminance(reference)]),
      difference: difference.concat([report.luminance(difference)]),
      reference_se: se ? se.concat([report.luminanceError(se)]) : null,
      z: se ? difference.map((d, c) => ratio(d, se[c])).concat(
        [ratio(report.luminance(difference), report.luminanceError(se))]) : null,
      ssim: report.pixel(data, "ssim", x, y),
      flip: report.pixel(data, "flip", x, y),
    };
  }

  function cell(tag, text, className) {
    const element = document.createElement(tag);
    element.textContent = text;
    if (className) {
      element.className = className;
    }
    return element;
  }

  function fill(section, data, x, y) {
    const box = tooltipElement();
    const values = valuesAt(data, x, y);
    const exr = report.exrPixels(section, data, x, y);
    box.dataset.view = section.dataset.view;
    box.dataset.x = String(x);
    box.dataset.y = String(y);
    box.dataset.exr = [exr.x0, exr.x1, exr.y0, exr.y1].join(" ");
    box.replaceChildren();
    const where = data.factor > 1
      ? "EXR pixels x " + exr.x0 + "–" + exr.x1 + ", y " + exr.y0 + "–" + exr.y1 +
        " (mean of " + data.factor + "×" + data.factor + ")"
      : "EXR pixel x " + exr.x0 + ", y " + exr.y0;
    box.appendChild(cell("div", section.dataset.view + " · " + where, "probe-where"));
    const table = document.createElement("table");
    const head = document.createElement("tr");
    for (const label of ["", "R", "G", "B", "lum"]) {
      head.appendChild(cell("th", label));
    }
    table.appendChild(head);
    for (const [name, label] of ROWS) {
      const row = document.createElement("tr");
      row.dataset.layer = name;
      row.appendChild(cell("th", label));
      const numbers = values[name];
      if (numbers) {
        row.dataset.values = JSON.stringify(numbers);
        for (const value of numbers) {
          row.appendChild(cell("td", report.format(value)));
        }
      } else {
        const missing = cell("td", "not recorded");
        missing.colSpan = 4;
        row.appendChild(missing);
      }
      table.appendChild(row);
    }
    box.appendChild(table);
    const extra = [];
    for (const name of ["ssim", "flip"]) {
      if (values[name]) {
        box.dataset[name] = String(values[name][0]);
        extra.push(name.toUpperCase() + " " + report.format(values[name][0]));
      }
    }
    extra.push("units: " + section.dataset.units);
    box.appendChild(cell("div", extra.join(" · "), "probe-units"));
  }

  function place(event) {
    const box = tooltipElement();
    const margin = 14;
    let left = event.clientX + margin, top = event.clientY + margin;
    if (left + box.offsetWidth > window.innerWidth) {
      left = event.clientX - margin - box.offsetWidth;
    }
    if (top + box.offsetHeight > window.innerHeight) {
      top = event.clientY - margin - box.offsetHeight;
    }
    box.style.left = Math.max(0, left) + "px";
    box.style.top = Math.max(0, top) + "px";
  }

  function mark(section, x, y) {
    for (const overlay of section.querySelectorAll("svg.overlay")) {
      let square = overlay.querySelector("rect.probe-mark");
      if (!square) {
        square = report.svg("rect", { class: "probe-mark", width: 1, height: 1 });
        overlay.appendChild(square);
      }
      if (x === null) {
        square.style.display = "none";
      } else {
        square.setAttribute("x", x);
        square.setAttribute("y", y);
        square.style.display = "";
      }
    }
  }

  function attach(section, data) {
    for (const viewport of section.querySelectorAll(".viewport")) {
      const layer = viewport.querySelector(".zoom");
      viewport.addEventListener("pointermove", (event) => {
        const at = report.pixelAt(layer, event, data.width, data.height);
        if (!at.inside) {
          return;
        }
        fill(section, data, at.x, at.y);
        mark(section, at.x, at.y);
        tooltipElement().hidden = false;
        place(event);
      });
      viewport.addEventListener("pointerleave", () => {
        tooltipElement().hidden = true;
        mark(section, null, null);
      });
    }
  }

  report.probe = { attach: attach, valuesAt: valuesAt };
})();
