/* caustics-harness report: the temporal section's animation player.
 *
 * Hand-written, no dependencies, no network. The animation is the animated WebP the
 * report wrote (Pillow, lossless): window.causticsTemporal[view] holds it as a data:
 * URI, because a file:// page may not read the file beside it. The browser's own
 * ImageDecoder (WebCodecs) decodes its frames; each is drawn on the canvas
 * unchanged (no colour conversion, no alpha), frame i of the file being frame i of
 * the sequence. Controls: play/pause, one frame back or forward, a frame slider.
 * Without ImageDecoder the file is shown as a plain image (it plays, without pause).
 *
 * State for tests and readers: the player's data-playing ("true"/"false"), the
 * canvas's data-frame (index shown), body's data-temporal-ready ("true"/"error").
 */
(function () {
  "use strict";

  function bytesOf(uri) {
    const text = atob(uri.slice(uri.indexOf(",") + 1));
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) {
      bytes[i] = text.charCodeAt(i);
    }
    return bytes;
  }

  async function decodeFrames(uri) {
    const decoder = new ImageDecoder({ data: bytesOf(uri), type: "image/webp",
      colorSpaceConversion: "none", premultiplyAlpha: "none" });
    await decoder.tracks.ready;
    const count = decoder.tracks.selectedTrack.frameCount;
    const frames = [];
    for (let i = 0; i < count; i++) {
      const result = await decoder.decode({ frameIndex: i });
      frames.push(await createImageBitmap(result.image, {
        colorSpaceConversion: "none", premultiplyAlpha: "none" }));
      result.image.close();
    }
    decoder.close();
    return frames;
  }

  function fallBack(player, uri, why) {
    player.dataset.mode = "fallback";
    player.querySelectorAll(".temporal-live").forEach((node) => { node.hidden = true; });
    const fallback = player.querySelector(".temporal-fallback");
    const image = fallback.querySelector("img");
    if (!image.getAttribute("src")) {
      image.src = uri;  // a self-contained page ships the file once, as the data: URI
    }
    fallback.hidden = false;
    const note = fallback.querySelector(".temporal-why");
    if (note) {
      note.textContent = why;
    }
  }

  async function setUp(player) {
    const uri = (window.causticsTemporal || {})[player.dataset.view];
    if (!uri) {
      throw new Error("no animation data for view " + player.dataset.view);
    }
    if (typeof ImageDecoder === "undefined") {
      fallBack(player, uri, "This browser has no ImageDecoder: the animation plays as an " +
        "image, without pause or steps.");
      return;
    }
    const frames = await decodeFrames(uri);
    const times = JSON.parse(player.dataset.times);
    const fps = parseFloat(player.dataset.fps);
    const canvas = player.querySelector("canvas.temporal-frame");
    const context = canvas.getContext("2d");
    const play = player.querySelector("button.temporal-play");
    const seek = player.querySelector("input.temporal-seek");
    const label = player.querySelector("output.temporal-label");
    let index = 0, playing = false, last = null;

    function show(i) {
      index = ((i % frames.length) + frames.length) % frames.length;
      context.drawImage(frames[index], 0, 0);
      canvas.dataset.frame = String(index);
      seek.value = String(index);
      const time = times[index] !== undefined ? times[index].toFixed(3) : "?";
      label.textContent = "frame " + (index + 1) + " / " + frames.length + ", τ = " + time + " s";
    }

    function tick(now) {
      if (!playing) {
        return;
      }
      if (last === null) {
        last = now;
      } else if (now - last >= 1000 / fps) {
        last = now;
        show(index + 1);
      }
      requestAnimationFrame(tick);
    }

    function setPlaying(on) {
      playing = on;
      player.dataset.playing = String(on);
      play.textContent = on ? "Pause" : "Play";
      play.setAttribute("aria-pressed", String(on));
      last = null;
      if (on) {
        requestAnimationFrame(tick);
      }
    }

    canvas.width = frames[0].width;
    canvas.height = frames[0].height;
    seek.max = String(frames.length - 1);
    play.addEventListener("click", () => setPlaying(!playing));
    player.querySelector("button.temporal-back").addEventListener("click", () => {
      setPlaying(false);
      show(index - 1);
    });
    player.querySelector("button.temporal-forward").addEventListener("click", () => {
      setPlaying(false);
      show(index + 1);
    });
    seek.addEventListener("input", () => {
      setPlaying(false);
      show(parseInt(seek.value, 10));
    });
    player.dataset.mode = "player";
    player.dataset.decodedFrames = String(frames.length);
    show(0);
    const still = window.matchMedia && window.matchMedia("(prefers-reduced-motion: reduce)");
    setPlaying(!(still && still.matches));
  }

  async function main() {
    const players = Array.from(document.querySelectorAll(".temporal-player[data-view]"));
    if (!players.length) {
      return;
    }
    await Promise.all(players.map(setUp));
    document.body.dataset.temporalReady = "true";
  }

  main().catch((error) => {
    console.error("caustics report (temporal): " + error);
    document.body.dataset.temporalReady = "error";
  });
})();
