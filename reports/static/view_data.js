/* caustics-harness report, shared part: the views' float data and helpers.
 *
 * Each view's data arrive in a script of their own (reports/panels.py, view_data):
 *   window.causticsData[view] = {width, height, factor,
 *                                layers: {name: {channels, base64}}}
 * with every layer little-endian float32 in C order, row 0 at the top of the display
 * (receiver maps flipped so +v points up). Layers: method, reference (3 channels),
 * reference_se (the reference's standard error sqrt(Var[mean]), 3 channels, when the
 * comparison carries the variance), ssim and flip (1 channel, when computed). A view
 * box-filtered down by `factor` holds box means (the page says so).
 *
 * window.causticsColormap = {name, base64}: the false-colour table, 256 RGB bytes,
 * drawn by reports.images.lookup_table from matplotlib's colormap.
 *
 * This part creates window.causticsReport, the namespace the other parts share.
 */
(function () {
  "use strict";

  const report = window.causticsReport = window.causticsReport || {};

  /* Rec. 709 luma weights for linear RGB, as reports/display.py LUMA. */
  report.LUMA = [0.2126, 0.7152, 0.0722];

  const littleEndian = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;

  function bytesOf(base64) {
    const text = atob(base64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) {
      bytes[i] = text.charCodeAt(i);
    }
    return bytes;
  }

  function floatsOf(base64) {
    const bytes = bytesOf(base64);
    if (littleEndian) {
      return new Float32Array(bytes.buffer);
    }
    const view = new DataView(bytes.buffer);
    const out = new Float32Array(bytes.length / 4);
    for (let i = 0; i < out.length; i++) {
      out[i] = view.getFloat32(4 * i, true);
    }
    return out;
  }

  /* The decoded float layers of one view ({width, height, factor, layers: {name:
   * {channels, values}}}), or null when the page ships none for it. */
  report.viewData = function (view) {
    const raw = (window.causticsData || {})[view];
    if (!raw) {
      return null;
    }
    const layers = {};
    for (const name of Object.keys(raw.layers)) {
      const layer = raw.layers[name];
      layers[name] = { channels: layer.channels, values: floatsOf(layer.base64) };
    }
    return { width: raw.width, height: raw.height, factor: raw.factor, layers: layers };
  };

  /* The false-colour table: Uint8Array of 256 RGB triplets (grey ramp without one). */
  report.colormap = (function () {
    const table = window.causticsColormap;
    if (table) {
      return bytesOf(table.base64);
    }
    const grey = new Uint8Array(768);
    for (let i = 0; i < 256; i++) {
      grey[3 * i] = grey[3 * i + 1] = grey[3 * i + 2] = i;
    }
    return grey;
  })();

  /* Values of one layer at display pixel (x, y): an array of its channels (the
   * float32 values exactly), or null when the view has no such layer. */
  report.pixel = function (data, name, x, y) {
    const layer = data.layers[name];
    if (!layer) {
      return null;
    }
    const c = layer.channels, i = c * (y * data.width + x);
    return Array.from(layer.values.subarray(i, i + c));
  };

  /* Linear luminance of an RGB triple (a single value is returned as is). */
  report.luminance = function (rgb) {
    if (rgb.length === 1) {
      return rgb[0];
    }
    return report.LUMA[0] * rgb[0] + report.LUMA[1] * rgb[1] + report.LUMA[2] * rgb[2];
  };

  /* method − reference per channel: the difference of the two float32 values, rounded
   * to float32 once, which is exactly <view>/signed (float64 difference, then float32). */
  report.difference = function (method, reference) {
    return method.map((value, c) => Math.fround(value - reference[c]));
  };

  /* Standard error of the luminance from the channels' standard errors: the upper
   * bound Σ_c w_c σ_c (exact for perfectly correlated channels; reports/profiles.py). */
  report.luminanceError = function (se) {
    return se.length === 1 ? se[0]
      : report.LUMA[0] * se[0] + report.LUMA[1] * se[1] + report.LUMA[2] * se[2];
  };

  /* The EXR pixels behind display pixel (x, y): columns x0..x1 and rows y0..y1 of the
   * stored array (receiver maps are stored with row 0 at v = vmin, shown flipped). */
  report.exrPixels = function (section, data, x, y) {
    const f = data.factor;
    const x0 = x * f, x1 = x0 + f - 1;
    if (section.dataset.flipped !== "true") {
      return { x0: x0, x1: x1, y0: y * f, y1: y * f + f - 1 };
    }
    const height = parseInt(section.dataset.fullHeight, 10);
    const top = height - 1 - y * f;
    return { x0: x0, x1: x1, y0: top - f + 1, y1: top };
  };

  /* A number for people: 5 significant digits, exponent form when far from 1. */
  report.format = function (value) {
    if (value === null || value === undefined || Number.isNaN(value)) {
      return "n/a";
    }
    if (value === 0) {
      return "0";
    }
    const size = Math.abs(value);
    return size >= 1e-3 && size < 1e5 ? value.toPrecision(5) : value.toExponential(4);
  };

  /* The display pixel under a pointer event over a viewport's zoom layer, clamped to
   * the grid; the layer's bounding box already includes the zoom transform. */
  report.pixelAt = function (zoomLayer, event, width, height) {
    const box = zoomLayer.getBoundingClientRect();
    const u = (event.clientX - box.left) / box.width;
    const v = (event.clientY - box.top) / box.height;
    return {
      x: Math.min(width - 1, Math.max(0, Math.floor(u * width))),
      y: Math.min(height - 1, Math.max(0, Math.floor(v * height))),
      inside: u >= 0 && u < 1 && v >= 0 && v < 1,
    };
  };

  /* True when a pointer-down starts a profile instead of a pan. */
  report.profileGesture = function (event) {
    const toggle = document.getElementById("profile-mode");
    return event.shiftKey || Boolean(toggle && toggle.checked);
  };

  const SVG = "http://www.w3.org/2000/svg";

  /* An SVG element with attributes (the namespace is a name, nothing is fetched). */
  report.svg = function (name, attributes) {
    const element = document.createElementNS(SVG, name);
    for (const key of Object.keys(attributes || {})) {
      element.setAttribute(key, attributes[key]);
    }
    return element;
  };
})();
