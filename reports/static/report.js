/* caustics-harness report: exposure control and A/B comparison for HDR images.
 *
 * Hand-written, no dependencies, no network. The HDR previews arrive as data: URIs
 * in window.causticsHdr[view][layer] (layer "method" or "reference"), each an RGB PNG
 * holding Ward's RGBE encoding in two stacked halves (reports/images.py):
 *   rows 0..H-1  : mantissas R, G, B       rows H..2H-1 : shared exponent E
 *   value = (byte + 0.5) * 2^(E - 136), and 0 where E = 0.
 * data: URIs keep the canvas untainted on file:// pages, so its pixels can be read.
 *
 * Tone curve, identical to harness.metrics.tonemap at exposure 0:
 *   t(x) = srgb(k x / (1 + k x)),  k = 2^stops / white
 * with white the view's white point (data-white) and stops the exposure slider.
 */
(function () {
  "use strict";

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

  function toneMap(hdr, k) {
    const out = new ImageData(hdr.width, hdr.height);
    const v = hdr.values, d = out.data;
    for (let i = 0, n = hdr.width * hdr.height; i < n; i++) {
      for (let c = 0; c < 3; c++) {
        const x = Math.max(v[3 * i + c], 0) * k;
        d[4 * i + c] = Math.round(255 * srgb(x / (1 + x)));
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

  async function setUpView(section, exposure) {
    const view = section.dataset.view;
    const sources = (window.causticsHdr || {})[view];
    if (!sources) {
      throw new Error("no HDR data for view " + view);
    }
    const white = parseFloat(section.dataset.white);
    const layers = {};
    for (const layer of ["method", "reference"]) {
      layers[layer] = await decodeRgbe(sources[layer]);
    }
    const ab = section.querySelector("canvas.ab");
    const split = section.querySelector("input.ab-split");
    let toned = {};

    function drawAb() {
      if (!ab) {
        return;
      }
      const a = toned.method, b = toned.reference;
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
      const k = Math.pow(2, parseFloat(exposure.value)) / white;
      for (const layer of ["method", "reference"]) {
        toned[layer] = toneMap(layers[layer], k);
        section.querySelectorAll('canvas.hdr[data-layer="' + layer + '"]').forEach(
          (canvas) => paint(canvas, toned[layer]));
      }
      drawAb();
    }

    exposure.addEventListener("input", render);
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
  }

  async function main() {
    const exposure = document.getElementById("exposure");
    const label = document.getElementById("exposure-value");
    if (!exposure) {
      return;
    }
    const update = () => { label.textContent = parseFloat(exposure.value).toFixed(2); };
    exposure.addEventListener("input", update);
    update();
    const sections = Array.from(document.querySelectorAll("section.view[data-view]"));
    await Promise.all(sections.map((section) => setUpView(section, exposure)));
    document.body.dataset.hdrReady = "true";
  }

  main().catch((error) => {
    console.error("caustics report: " + error);
    document.body.dataset.hdrReady = "error";
  });
})();
