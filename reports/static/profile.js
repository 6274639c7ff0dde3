/* caustics-harness report: line profiles, method against reference.
 *
 * Shift+drag on any panel of a view (or drag, with "drag draws a profile" ticked)
 * draws a line; the view's profile plot then shows the luminance of the method and
 * of the reference along it, with the reference's ±2σ band (σ its standard error,
 * the upper bound Σ_c w_c σ_c of reports/profiles.py), on a logarithmic axis in the
 * log and false-colour display modes. Receiver maps open with their default profile
 * (the section's data-profile: the horizontal line through the reference's peak in
 * the caustic region, also written as CSV by reports/profiles.py).
 *
 * Sampling, as reports/profiles.py line_pixels: from pixel (x0, y0) to (x1, y1),
 * n = max(|x1 − x0|, |y1 − y0|) + 1 samples, x_i = x0 + floor(i (x1 − x0) / (n − 1) + 1/2)
 * (y likewise): one pixel per sample, no interpolation, so every sample is a value of
 * the data. The plot (inline SVG) keeps them in data-samples (JSON: display and EXR
 * pixels, each layer's channels and luminance) and offers them as CSV.
 */
(function () {
  "use strict";

  const report = window.causticsReport;
  const WIDTH = 640, HEIGHT = 250;
  const MARGIN = { left: 70, right: 14, top: 26, bottom: 40 };
  const COLOURS = { method: "#d95f02", reference: "#1b6ac9", band: "rgba(27, 106, 201, 0.22)" };
  const CSV_COLUMNS = [
    "sample", "x", "y", "method_r", "method_g", "method_b", "method_lum",
    "reference_r", "reference_g", "reference_b", "reference_lum",
    "reference_se_r", "reference_se_g", "reference_se_b", "reference_se_lum",
  ];

  /* Display pixels of the line from start to end, both included. */
  function linePixels(start, end) {
    const dx = end.x - start.x, dy = end.y - start.y;
    const steps = Math.max(Math.abs(dx), Math.abs(dy));
    const xs = [], ys = [];
    for (let i = 0; i <= steps; i++) {
      xs.push(steps === 0 ? start.x : start.x + Math.floor(i * dx / steps + 0.5));
      ys.push(steps === 0 ? start.y : start.y + Math.floor(i * dy / steps + 0.5));
    }
    return { xs: xs, ys: ys };
  }

  function samplesAlong(section, data, start, end) {
    const line = linePixels(start, end);
    const out = { displayX: line.xs, displayY: line.ys, x: [], y: [], method: [],
                  reference: [], stderr: [], methodLum: [], referenceLum: [], stderrLum: [] };
    for (let i = 0; i < line.xs.length; i++) {
      const x = line.xs[i], y = line.ys[i];
      const exr = report.exrPixels(section, data, x, y);
      const method = report.pixel(data, "method", x, y);
      const reference = report.pixel(data, "reference", x, y);
      const se = report.pixel(data, "reference_se", x, y);
      out.x.push(exr.x0);
      out.y.push(exr.y0);
      out.method.push(method);
      out.reference.push(reference);
      out.methodLum.push(report.luminance(method));
      out.referenceLum.push(report.luminance(reference));
      out.stderr.push(se);
      out.stderrLum.push(se ? report.luminanceError(se) : null);
    }
    return out;
  }

  /* About five round tick values covering [low, high]. */
  function linearTicks(low, high) {
    const raw = (high - low) / 5;
    const power = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * power).find((s) => s >= raw);
    const ticks = [];
    for (let t = Math.ceil(low / step) * step; t <= high + 1e-9 * step; t += step) {
      ticks.push(Math.abs(t) < 1e-12 * step ? 0 : t);
    }
    return ticks;
  }

  /* A tick value without the float noise of its computation (0.30000000000000004). */
  function tickLabel(value) {
    const size = Math.abs(value);
    if (value === 0 || (size >= 1e-3 && size < 1e5)) {
      return String(Number(value.toPrecision(6)));
    }
    return value.toExponential(0);
  }

  function axes(low, high, log) {
    if (log) {
      const a = Math.floor(Math.log10(low)), b = Math.ceil(Math.log10(high));
      const ticks = [];
      for (let e = a; e <= b; e++) {
        ticks.push(Math.pow(10, e));
      }
      return { low: ticks[0], high: ticks[ticks.length - 1], ticks: ticks,
               map: (v) => (Math.log10(v) - a) / Math.max(b - a, 1) };
    }
    const ticks = linearTicks(low, high);
    return { low: low, high: high, ticks: ticks, map: (v) => (v - low) / (high - low) };
  }

  function plot(container, samples, options) {
    const n = samples.methodLum.length;
    const hasBand = samples.stderrLum.every((s) => s !== null);
    const upper = samples.referenceLum.map((r, i) => r + (hasBand ? 2 * samples.stderrLum[i] : 0));
    const lower = samples.referenceLum.map((r, i) => r - (hasBand ? 2 * samples.stderrLum[i] : 0));
    const all = samples.methodLum.concat(upper, lower).filter(Number.isFinite);
    let low = Math.min(0, ...all), high = Math.max(...all);
    if (options.log) {
      const positive = all.filter((v) => v > 0);
      high = positive.length ? Math.max(...positive) : 1;
      low = Math.max(positive.length ? Math.min(...positive) : high, high * 1e-4);
    }
    if (!(high > low)) {
      high = low + 1;
    }
    const axis = axes(low, high, options.log);
    const plotW = WIDTH - MARGIN.left - MARGIN.right, plotH = HEIGHT - MARGIN.top - MARGIN.bottom;
    const px = (i) => MARGIN.left + plotW * (n > 1 ? i / (n - 1) : 0.5);
    const py = (v) => {
      const clipped = options.log ? Math.max(v, axis.low) : v;
      return MARGIN.top + plotH * (1 - Math.min(1.05, Math.max(-0.05, axis.map(clipped))));
    };
    const svg = report.svg("svg", {
      class: "profile-svg", viewBox: "0 0 " + WIDTH + " " + HEIGHT, width: WIDTH,
      height: HEIGHT, role: "img", "aria-label": options.title,
    });
    svg.dataset.samples = JSON.stringify(samples);
    svg.dataset.scale = options.log ? "log" : "linear";
    svg.appendChild(report.svg("rect", { x: MARGIN.left, y: MARGIN.top, width: plotW,
                                         height: plotH, class: "frame" }));
    for (const tick of axis.ticks) {
      const y = py(tick);
      svg.appendChild(report.svg("line", { x1: MARGIN.left, x2: MARGIN.left + plotW, y1: y,
                                           y2: y, class: "grid" }));
      const label = report.svg("text", { x: MARGIN.left - 4, y: y + 4, "text-anchor": "end" });
      label.textContent = tickLabel(tick);
      svg.appendChild(label);
    }
    for (const i of [0, Math.floor((n - 1) / 2), n - 1]) {
      const label = report.svg("text", { x: px(i), y: MARGIN.top + plotH + 14,
                                         "text-anchor": "middle" });
      label.textContent = String(i);
      svg.appendChild(label);
    }
    const xLabel = report.svg("text", { x: MARGIN.left + plotW / 2, y: HEIGHT - 6,
                                        "text-anchor": "middle" });
    xLabel.textContent = "sample along the line (one pixel each)";
    svg.appendChild(xLabel);
    const yLabel = report.svg("text", { x: 12, y: MARGIN.top + plotH / 2, "text-anchor": "middle",
                                        transform: "rotate(-90 12 " + (MARGIN.top + plotH / 2) + ")" });
    yLabel.textContent = "luminance (" + options.units + ")";
    svg.appendChild(yLabel);
    if (hasBand) {
      const points = upper.map((v, i) => px(i) + "," + py(v))
        .concat(lower.map((v, i) => px(i) + "," + py(v)).reverse());
      svg.appendChild(report.svg("polygon", { points: points.join(" "), fill: COLOURS.band,
                                              "data-series": "reference ± 2σ" }));
    }
    for (const [name, values] of [["reference", samples.referenceLum],
                                  ["method", samples.methodLum]]) {
      svg.appendChild(report.svg("polyline", {
        points: values.map((v, i) => px(i) + "," + py(v)).join(" "), fill: "none",
        stroke: COLOURS[name], "stroke-width": 1.5, "data-series": name,
      }));
    }
    const legend = [["method", COLOURS.method], ["reference", COLOURS.reference]];
    if (hasBand) {
      legend.push(["reference ± 2σ", COLOURS.band]);
    }
    legend.forEach(([label, colour], k) => {
      const x = MARGIN.left + 10 + 130 * k;
      // Above the plot, clear of the curves.
      svg.appendChild(report.svg("rect", { x: x, y: 6, width: 14, height: 8, fill: colour }));
      const text = report.svg("text", { x: x + 18, y: 14 });
      text.textContent = label;
      svg.appendChild(text);
    });
    container.replaceChildren(svg);
    return svg;
  }

  function csv(samples) {
    const rows = [CSV_COLUMNS.join(",")];
    for (let i = 0; i < samples.x.length; i++) {
      const se = samples.stderr[i];
      rows.push([i, samples.x[i], samples.y[i], ...samples.method[i], samples.methodLum[i],
                 ...samples.reference[i], samples.referenceLum[i],
                 ...(se ? se.concat([samples.stderrLum[i]]) : ["", "", "", ""])].join(","));
    }
    return rows.join("\n") + "\n";
  }

  function drawLine(section, start, end) {
    for (const overlay of section.querySelectorAll("svg.overlay")) {
      let line = overlay.querySelector("line.profile-line");
      if (!line) {
        line = report.svg("line", { class: "profile-line" });
        overlay.appendChild(line);
      }
      // Pixel centres: pixel (x, y) covers [x, x + 1] × [y, y + 1] of the overlay.
      line.setAttribute("x1", start.x + 0.5);
      line.setAttribute("y1", start.y + 0.5);
      line.setAttribute("x2", end.x + 0.5);
      line.setAttribute("y2", end.y + 0.5);
    }
  }

  function show(section, data, profile) {
    const box = section.querySelector("div.profile");
    if (!box) {
      return;
    }
    section.causticsProfile = profile;
    drawLine(section, profile.start, profile.end);
    const samples = samplesAlong(section, data, profile.start, profile.end);
    const mode = document.querySelector('input[name="display-mode"]:checked');
    const log = Boolean(mode && mode.value !== "linear");
    const first = samples.x.length - 1;
    const title = profile.label + ": EXR pixels (" + samples.x[0] + ", " + samples.y[0] +
      ") → (" + samples.x[first] + ", " + samples.y[first] + "), " + samples.x.length +
      " samples";
    box.hidden = false;
    box.querySelector(".profile-title").textContent = title;
    plot(box.querySelector(".profile-plot"), samples,
         { log: log, units: section.dataset.units, title: title });
    const info = box.querySelector(".profile-info");
    info.replaceChildren();
    const link = document.createElement("a");
    link.className = "profile-download";
    link.download = "profile_" + section.dataset.view + "_" + samples.x[0] + "_" + samples.y[0] +
      "_" + samples.x[first] + "_" + samples.y[first] + ".csv";
    link.href = "data:text/csv;charset=utf-8," + encodeURIComponent(csv(samples));
    link.textContent = "these samples as CSV";
    info.append("Luminance along the line; band: reference ± 2 standard errors. ",
                data.factor > 1 ? "Preview pixels (means of " + data.factor + "×" + data.factor +
                " EXR pixels). " : "", link);
  }

  function attach(section, data) {
    let drag = null;
    for (const viewport of section.querySelectorAll(".viewport")) {
      const layer = viewport.querySelector(".zoom");
      viewport.addEventListener("pointerdown", (event) => {
        if (event.button !== 0 || !report.profileGesture(event)) {
          return;
        }
        event.preventDefault();
        const at = report.pixelAt(layer, event, data.width, data.height);
        drag = { id: event.pointerId, start: at };
        viewport.setPointerCapture(event.pointerId);
        drawLine(section, at, at);
      });
      viewport.addEventListener("pointermove", (event) => {
        if (drag && event.pointerId === drag.id) {
          drawLine(section, drag.start, report.pixelAt(layer, event, data.width, data.height));
        }
      });
      viewport.addEventListener("pointerup", (event) => {
        if (!drag || event.pointerId !== drag.id) {
          return;
        }
        const end = report.pixelAt(layer, event, data.width, data.height);
        const start = drag.start;
        drag = null;
        if (start.x !== end.x || start.y !== end.y) {
          show(section, data, { start: start, end: end, label: "Profile" });
        } else if (section.causticsProfile) {
          drawLine(section, section.causticsProfile.start, section.causticsProfile.end);
        }
      });
    }
    const line = (section.dataset.profile || "").split(" ").map(Number);
    if (line.length === 4 && line.every(Number.isInteger)) {
      show(section, data, { start: { x: line[0], y: line[1] }, end: { x: line[2], y: line[3] },
                            label: "Default profile (through the reference's caustic peak)" });
    }
  }

  /* Draw the section's profile again (the display mode sets the axis). */
  function redraw(section, data) {
    if (section.causticsProfile) {
      show(section, data, section.causticsProfile);
    }
  }

  report.profile = { attach: attach, redraw: redraw, linePixels: linePixels };
})();
