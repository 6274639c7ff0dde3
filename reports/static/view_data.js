/* caustics-harness report, shared part: the views' float data and helpers.
 *
 * Each view's sizes arrive in a script of their own (reports/page_data.py):
 *   window.causticsData[view] = {width, height, factor, encoding,
 *                                layers: {name: {channels, blob}}}
 * and each layer's packed bytes in a blob script, shared by the pages of one scene
 * (_data/<blob>.js beside the scene folders, inline on a self-contained page):
 *   window.causticsBlobs[blob] = base64 of the packed bytes.
 * Packed: float32 bit patterns, channels after the first XORed with the one before,
 * channels planar, each row differenced from the left (mod 2^32), the four bytes of
 * the values in four planes, zlib deflate (reports/page_data.py pack).
 *
 * Layers, row 0 at the top of the display (receiver maps flipped so +v points up):
 * reference, difference (method − reference, the float32 <view>/signed) and
 * method_exceptions (3 channels); reference_se (the reference's standard error
 * sqrt(Var[mean]), 3 channels, when the comparison carries the variance); ssim and
 * flip (1 channel, when computed). The method is fround(reference + difference),
 * except where method_exceptions holds a number. Every value is within 0.05 % of
 * the comparison's float32 (reports/page_data.py). A view box-filtered down by
 * `factor` holds box means (the page says so).
 *
 * window.causticsColormap = {name, base64}: the false-colour table, 256 RGB bytes,
 * drawn by reports.images.lookup_table from matplotlib's colormap.
 * window.causticsLuma = [wR, wG, wB]: the luminance weights (scenes/colour.py LUMA).
 *
 * This part creates window.causticsReport, the namespace the other parts share.
 */
(function () {
  "use strict";

  const report = window.causticsReport = window.causticsReport || {};

  /* Rec. 709 luma weights for linear RGB: scenes/colour.py LUMA, which the page's
   * hdr.js sets (reports/panels.py hdr_script); the page has no copy of its own. */
  if (!Array.isArray(window.causticsLuma) || window.causticsLuma.length !== 3) {
    throw new Error("window.causticsLuma (the luminance weights) was not loaded (hdr.js)");
  }
  report.LUMA = window.causticsLuma;

  function bytesOf(base64) {
    const text = atob(base64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) {
      bytes[i] = text.charCodeAt(i);
    }
    return bytes;
  }

  /* The packing reports/page_data.py pack writes; anything else is refused. */
  const ENCODING = "f32-round10-xor-delta-shuffle-deflate";

  async function inflate(bytes) {
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }

  /* The float32 values (interleaved channels, C order) of one packed layer. The
   * uint32 patterns are rebuilt arithmetically, so byte order does not matter. */
  async function unpack(key, width, height, channels) {
    const base64 = (window.causticsBlobs || {})[key];
    if (base64 === undefined) {
      throw new Error("data blob " + key + " was not loaded (_data/" + key + ".js)");
    }
    const bytes = await inflate(bytesOf(base64));
    const n = width * height * channels;
    if (bytes.length !== 4 * n) {
      throw new Error("data blob " + key + " holds " + bytes.length + " bytes, not " + 4 * n);
    }
    const bits = new Uint32Array(n);
    for (let c = 0; c < channels; c++) {
      for (let y = 0; y < height; y++) {
        const row = (c * height + y) * width;
        let value = 0;
        for (let x = 0; x < width; x++) {
          const i = row + x;
          const delta = bytes[i] | (bytes[n + i] << 8) | (bytes[2 * n + i] << 16) |
            (bytes[3 * n + i] << 24);
          value = (value + delta) >>> 0;
          bits[(y * width + x) * channels + c] = value;
        }
      }
    }
    for (let p = 0; p < n; p += channels) {
      for (let c = 1; c < channels; c++) {
        bits[p + c] ^= bits[p + c - 1];
      }
    }
    return new Float32Array(bits.buffer);
  }

  const decoded = {};

  /* The decoded float layers of one view ({width, height, factor, layers: {name:
   * {channels, values}}}, the method composed), or null when the page ships none
   * for it. Decoded once per view. */
  report.viewData = function (view) {
    const raw = (window.causticsData || {})[view];
    if (!raw) {
      return Promise.resolve(null);
    }
    if (!decoded[view]) {
      decoded[view] = decodeView(raw);
    }
    return decoded[view];
  };

  async function decodeView(raw) {
    if (raw.encoding !== ENCODING) {
      throw new Error("unknown data encoding " + raw.encoding);
    }
    const layers = {};
    await Promise.all(Object.keys(raw.layers).map(async (name) => {
      const layer = raw.layers[name];
      layers[name] = { channels: layer.channels,
                       values: await unpack(layer.blob, raw.width, raw.height, layer.channels) };
    }));
    const reference = layers.reference.values, difference = layers.difference.values;
    const exceptions = layers.method_exceptions.values;
    const method = new Float32Array(reference.length);
    for (let i = 0; i < method.length; i++) {
      // Float32Array stores fround(reference + difference) of the two float32 values.
      method[i] = Number.isNaN(exceptions[i]) ? reference[i] + difference[i] : exceptions[i];
    }
    delete layers.method_exceptions;
    layers.method = { channels: layers.reference.channels, values: method };
    return { width: raw.width, height: raw.height, factor: raw.factor, layers: layers };
  }

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
