/* caustics-harness report, main part: exposure, display mode and A/B comparison of
 * the HDR images; then zoom (zoom.js), the probe (probe.js) and profiles
 * (profile.js) on every view. Hand-written, no dependencies, no network.
 *
 * Pixels come from each view's float32 data (view_data.js). A view without them
 * falls back to its HDR previews in window.causticsHdr[view][layer], each an RGB PNG
 * data: URI holding Ward's RGBE encoding in two stacked halves (reports/images.py):
 *   rows 0..H-1  : mantissas R, G, B       rows H..2H-1 : shared exponent E
 *   value = (byte + 0.5) * 2^(E - 136), and 0 where E = 0.
 * data: URIs keep the canvas untainted on file:// pages, so its pixels can be read.
 *
 * Display modes, with white the view's white point (data-white), peak the largest
 * reference luminance of the view (data-peak; 10 white when there is none) and stops
 * the exposure slider:
 *   linear        t(x) = srgb(k x / (1 + k x)) per channel, k = 2^stops / white: at
 *                 stops 0 identical to harness.metrics.tonemap (the curve SSIM uses);
 *   log           grey g = clamp((log10 L − lo) / 4, 0, 1), L the luminance,
 *                 hi = log10(peak / 2^stops), lo = hi − 4: four decades below the
 *                 reference's peak, as caustics span three orders of magnitude or
 *                 more and peak far above the white point (a 99th percentile);
 *   false colour  the same g through the colormap table (window.causticsColormap).
 * Each view's colour bar shows the mode's scale for the view, in its units.
 */
(function () {
  "use strict";

  const report = window.causticsReport;
  const DECADES = 4;

  function srgb(x) {
    return x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055;
  }

  async function decodeRgbe(uri) {
    const image = new Image();
    image.src = uri;
    await image.decode();
    const bitmap = await createImageBitmap(image, {
      colorSpaceConversion: "none", premultiplyAlpha: "none",
    });
    const w = bitmap.width, h = bitmap.height / 2;
    const canvas = document.createElement("canvas");
    canvas.width = bitmap.width;
    canvas.height = bitmap.height;
    const ctx = canvas.getContext("2d", { willReadFrequently: true });
    ctx.drawImage(bitmap, 0, 0);
    const bytes = ctx.getImageData(0, 0, w, 2 * h).data;
    const values = new Float32Array(w * h * 3);
    for (let i = 0; i < w * h; i++) {
      const e = bytes[4 * (i + w * h)];
      const f = e > 0 ? Math.pow(2, e - 136) : 0;
      for (let c = 0; c < 3; c++) {
        values[3 * i + c] = e > 0 ? (bytes[4 * i + c] + 0.5) * f : 0;
      }
    }
    return { width: w, height: h, values: values };
  }

  /* The log modes' position g in [0, 1] of luminance L (0 for L <= 0 or NaN). */
  function logPosition(luminance, low) {
    if (!(luminance > 0)) {
      return 0;
    }
    const g = (Math.log10(luminance) - low) / DECADES;
    return Math.min(1, Math.max(0, g));
  }

  /* The scales of a view at an exposure: k of the linear curve, and the log modes'
   * range [10^low, 10^high] of luminance. */
  function scalesOf(section, stops) {
    const white = parseFloat(section.dataset.white);
    const peak = parseFloat(section.dataset.peak);
    const high = Math.log10(peak > 0 ? peak : 10 * white) - stops * Math.log10(2);
    return { k: Math.pow(2, stops) / white, low: high - DECADES, high: high };
  }

  /* 8-bit RGBA of linear RGB values (3 per pixel) in a display mode. */
  function display(image, mode, scale) {
    const out = new ImageData(image.width, image.height);
    const v = image.values, d = out.data, lut = report.colormap, w = report.LUMA;
    const k = scale.k, low = scale.low;
    for (let i = 0, n = image.width * image.height; i < n; i++) {
      if (mode === "linear") {
        for (let c = 0; c < 3; c++) {
          const x = Math.max(v[3 * i + c], 0) * k;
          d[4 * i + c] = Math.round(255 * srgb(x / (1 + x)));
        }
      } else {
        const lum = w[0] * v[3 * i] + w[1] * v[3 * i + 1] + w[2] * v[3 * i + 2];
        const level = Math.round(255 * logPosition(lum, low));
        for (let c = 0; c < 3; c++) {
          d[4 * i + c] = mode === "log" ? level : lut[3 * level + c];
        }
      }
      d[4 * i + 3] = 255;
    }
    return out;
  }

  function paint(canvas, pixels) {
    canvas.width = pixels.width;
    canvas.height = pixels.height;
    canvas.getContext("2d").putImageData(pixels, 0, 0);
  }

  /* The view's colour bar: the mode's grey or colour ramp and its luminance range. */
  function drawBar(section, mode, scale) {
    const canvas = section.querySelector("canvas.mode-bar");
    if (!canvas) {
      return;
    }
    const units = section.dataset.units;
    const width = canvas.width, height = canvas.height;
    const ramp = { width: width, height: height, values: new Float32Array(3 * width * height) };
    let low, high, label;
    if (mode === "linear") {
      // Luminance 0 .. 4 / k, where the curve reaches srgb(0.8).
      low = 0;
      high = 4 / scale.k;
      label = "linear, tone-mapped (" + units + ")";
    } else {
      low = Math.pow(10, scale.low);
      high = Math.pow(10, scale.high);
      label = "log₁₀ luminance (" + units + ")";
    }
    for (let x = 0; x < width; x++) {
      const p = x / (width - 1);
      const value = mode === "linear" ? p * high
        : Math.pow(10, scale.low + p * DECADES);
      for (let y = 0; y < height; y++) {
        ramp.values.fill(value, 3 * (y * width + x), 3 * (y * width + x) + 3);
      }
    }
    canvas.getContext("2d").putImageData(display(ramp, mode, scale), 0, 0);
    canvas.dataset.low = String(low);
    canvas.dataset.high = String(high);
    const bar = canvas.closest("figure.mode-bar");
    bar.querySelector(".bar-low").textContent = report.format(low);
    bar.querySelector(".bar-label").textContent = label;
    bar.querySelector(".bar-high").textContent = report.format(high);
  }

  async function layersOf(section, data) {
    if (data) {
      const layers = {};
      for (const name of ["method", "reference"]) {
        layers[name] = { width: data.width, height: data.height,
                         values: data.layers[name].values };
      }
      return layers;
    }
    const sources = (window.causticsHdr || {})[section.dataset.view];
    if (!sources) {
      return null;
    }
    const layers = {};
    for (const name of ["method", "reference"]) {
      layers[name] = await decodeRgbe(sources[name]);
    }
    return layers;
  }

  async function setUpView(section, controls) {
    const data = await report.viewData(section.dataset.view);
    const layers = await layersOf(section, data);
    report.zoom.attach(section);
    if (!layers) {
      return;  // maps only: nothing to tone-map
    }
    const ab = section.querySelector("canvas.ab");
    const split = section.querySelector("input.ab-split");
    const shown = {};
    let lastMode = null;

    function drawAb() {
      if (!ab) {
        return;
      }
      const a = shown.method, b = shown.reference;
      const cut = Math.round(a.width * parseFloat(split.value) / 100);
      const mixed = new ImageData(new Uint8ClampedArray(b.data), b.width, b.height);
      for (let y = 0; y < a.height; y++) {
        const row = 4 * y * a.width;
        mixed.data.set(a.data.subarray(row, row + 4 * cut), row);
      }
      paint(ab, mixed);
      ab.dataset.split = String(cut);
    }

    function render() {
      const scale = scalesOf(section, parseFloat(controls.exposure.value));
      const mode = controls.mode();
      for (const name of ["method", "reference"]) {
        shown[name] = display(layers[name], mode, scale);
        section.querySelectorAll('canvas.hdr[data-layer="' + name + '"]').forEach(
          (canvas) => paint(canvas, shown[name]));
      }
      drawAb();
      drawBar(section, mode, scale);
      section.dataset.mode = mode;
      if (data && lastMode !== null && mode !== lastMode) {
        report.profile.redraw(section, data);
      }
      lastMode = mode;
    }

    controls.onChange(render);
    if (ab && split) {
      split.addEventListener("input", drawAb);
      // Hover swap: the split follows the pointer while it is over the image.
      ab.addEventListener("pointermove", (event) => {
        const box = ab.getBoundingClientRect();
        split.value = String(Math.min(100, Math.max(0,
          100 * (event.clientX - box.left) / box.width)));
        drawAb();
      });
    }
    render();
    if (data) {
      report.probe.attach(section, data);
      report.profile.attach(section, data);
    }
  }

  async function main() {
    const exposure = document.getElementById("exposure");
    const label = document.getElementById("exposure-value");
    if (!exposure) {
      return;
    }
    const modes = Array.from(document.querySelectorAll('input[name="display-mode"]'));
    const listeners = [];
    const controls = {
      exposure: exposure,
      mode: () => (modes.find((m) => m.checked) || { value: "linear" }).value,
      onChange: (listener) => listeners.push(listener),
    };
    const changed = () => listeners.forEach((listener) => listener());
    const update = () => { label.textContent = parseFloat(exposure.value).toFixed(2); };
    exposure.addEventListener("input", update);
    exposure.addEventListener("input", changed);
    modes.forEach((m) => m.addEventListener("change", changed));
    update();
    const sections = Array.from(document.querySelectorAll("section.view[data-view]"));
    await Promise.all(sections.map((section) => setUpView(section, controls)));
    document.body.dataset.hdrReady = "true";
  }

  main().catch((error) => {
    console.error("caustics report: " + error);
    document.body.dataset.hdrReady = "error";
  });
})();
