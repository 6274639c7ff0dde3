/* caustics-harness report: zoom and pan, in sync across every panel of a view.
 *
 * Every image panel is a viewport (div.viewport, overflow hidden) holding a zoom
 * layer (div.zoom: the canvas or image and its SVG overlay). One state per view,
 * (s, tx, ty), places every layer alike:
 *   screen = t + s · q,   q the untransformed position in the viewport,
 * with t in units of the viewport's size, so panels of different sizes (the A/B
 * image is twice as wide) show the same part of the image.
 *
 * Wheel: zoom about the pointer, keeping the image point under it fixed:
 *   u = (p − t) / s  (the point, in image units),   t' = p − u · s'.
 * Drag: pan. Double-click: back to the whole image. The image always covers its
 * viewport: 1 ≤ s ≤ MAX_SCALE and 1 − s ≤ t ≤ 0.
 * Each layer carries the state in data-zoom ("s tx ty") for tests and tools.
 */
(function () {
  "use strict";

  const report = window.causticsReport;
  const MAX_SCALE = 64;

  function clamp(value, low, high) {
    return Math.min(high, Math.max(low, value));
  }

  function attach(section) {
    const viewports = Array.from(section.querySelectorAll(".viewport"));
    const state = { s: 1, tx: 0, ty: 0 };

    function apply() {
      state.tx = clamp(state.tx, 1 - state.s, 0);
      state.ty = clamp(state.ty, 1 - state.s, 0);
      // Percentages of a translate are of the layer's own size, the viewport's inside.
      const transform = "translate(" + (100 * state.tx) + "%, " + (100 * state.ty) +
        "%) scale(" + state.s + ")";
      for (const viewport of viewports) {
        const layer = viewport.querySelector(".zoom");
        layer.style.transform = transform;
        layer.dataset.zoom = state.s + " " + state.tx + " " + state.ty;
      }
      section.dataset.zoom = state.s + " " + state.tx + " " + state.ty;
    }

    function onWheel(event) {
      event.preventDefault();
      const box = event.currentTarget.getBoundingClientRect();
      const px = (event.clientX - box.left) / box.width;
      const py = (event.clientY - box.top) / box.height;
      // Lines and pages scroll in bigger steps than pixels.
      const delta = event.deltaY * (event.deltaMode === 1 ? 16 : event.deltaMode === 2 ? 400 : 1);
      const scale = clamp(state.s * Math.exp(-0.002 * delta), 1, MAX_SCALE);
      const u = (px - state.tx) / state.s, v = (py - state.ty) / state.s;
      state.tx = px - u * scale;
      state.ty = py - v * scale;
      state.s = scale;
      apply();
    }

    let drag = null;

    function onDown(event) {
      if (event.button !== 0 || report.profileGesture(event)) {
        return;
      }
      // No text selection or image drag: either would scroll the clipped viewport.
      event.preventDefault();
      const box = event.currentTarget.getBoundingClientRect();
      drag = { id: event.pointerId, x: event.clientX, y: event.clientY,
               w: box.width, h: box.height, tx: state.tx, ty: state.ty };
      event.currentTarget.setPointerCapture(event.pointerId);
      event.currentTarget.classList.add("panning");
    }

    function onMove(event) {
      if (!drag || event.pointerId !== drag.id) {
        return;
      }
      state.tx = drag.tx + (event.clientX - drag.x) / drag.w;
      state.ty = drag.ty + (event.clientY - drag.y) / drag.h;
      apply();
    }

    function onUp(event) {
      if (drag && event.pointerId === drag.id) {
        event.currentTarget.classList.remove("panning");
        drag = null;
      }
    }

    for (const viewport of viewports) {
      viewport.addEventListener("wheel", onWheel, { passive: false });
      viewport.addEventListener("pointerdown", onDown);
      viewport.addEventListener("pointermove", onMove);
      viewport.addEventListener("pointerup", onUp);
      viewport.addEventListener("pointercancel", onUp);
      viewport.addEventListener("dragstart", (event) => event.preventDefault());
      viewport.addEventListener("dblclick", () => {
        state.s = 1;
        state.tx = state.ty = 0;
        apply();
      });
    }
    apply();
  }

  report.zoom = { attach: attach };
})();
