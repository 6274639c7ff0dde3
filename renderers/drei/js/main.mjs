// drei's Caustics (@pmndrs/vanilla, the algorithm of @react-three/drei's <Caustics>)
// on a scene that `caustics export` wrote, in one WebGL2 page. esbuild bundles this
// file with three and @pmndrs/vanilla from the project's JavaScript workspace
// (renderers/web/node_modules) into one script; renderers/drei/driver.py serves it,
// the page and the .glb from a route handler and calls
//
//     await window.dreiCaustics.run(config)  ->  result  (both plain JSON)
//
// config (every length in metres, every vector in glTF axes shifted so that the
// receiver plane is y = 0: the "drei frame"; renderers/drei/params.py makes it):
//   glb               URL of the exported scene
//   offset            [0, -h, 0]: added to the whole glTF scene (h the receiver height)
//   objects           node names of the caustic objects ("object_0", ...)
//   receivers         node names of the receivers ("receiver_0")
//   passes            one per distinct IOR: {ior}; each gives one caustic texture
//   caustics          the component's options: lightSource (towards the light),
//                     intensity, color, resolution, worldRadius, near, backside,
//                     backsideIOR
//   camera            {width, height}: the camera image's size in pixels
//   albedo            per receiver, linear RGB (its Lambertian material)
//   directLighting    the light shades the receivers directly (the scene's switch)
//   shadows           the objects cast shadow-mapped shadows
//   repeats           timed repeats after one warm-up
//
// result: front and back (per pass, base64 of float32 R of the component's front and
// back caustic render targets, res x res, row 0 at the texture's t = 0; back null
// without backside), lightCameras (per pass, the projection and view matrices,
// column-major, and extent of the component's orthographic light camera), camera
// (base64 float32 RGBA, width x height, row 0 at the image's bottom), timings (ms:
// caustics per pass and camera, each the median of `repeats`), timer (what measured
// them), and what the browser offered.
import * as THREE from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { Caustics } from "@pmndrs/vanilla";

const TIMER_EXTENSION = "EXT_disjoint_timer_query_webgl2";

function base64(typed) {
  // Float32Array -> base64 of its little-endian bytes, in chunks (apply's argument limit).
  const bytes = new Uint8Array(typed.buffer, typed.byteOffset, typed.byteLength);
  let text = "";
  for (let i = 0; i < bytes.length; i += 0x8000) {
    text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(text);
}

function median(values) {
  const sorted = [...values].sort((a, b) => a - b);
  const mid = sorted.length >> 1;
  return sorted.length % 2 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
}

function nextFrame() {
  return new Promise((resolve) => setTimeout(resolve, 0));
}

// Time one piece of GPU work. With EXT_disjoint_timer_query_webgl2: a TIME_ELAPSED
// query around it, polled until available (a disjoint event voids it: null).
// Always also the wall time: performance.now() around the work and `sync`, a
// one-pixel readPixels of the target it wrote last, which returns only once the GPU
// has finished writing it (gl.finish alone returns earlier in Chromium).
async function timeWork(gl, ext, work, sync) {
  let query = null;
  if (ext) {
    query = gl.createQuery();
    gl.beginQuery(ext.TIME_ELAPSED_EXT, query);
  }
  const start = performance.now();
  work();
  if (ext) gl.endQuery(ext.TIME_ELAPSED_EXT);
  gl.finish();
  sync();
  const wallMs = performance.now() - start;
  let gpuMs = null;
  if (query) {
    for (let i = 0; i < 1000; i++) {
      if (gl.getQueryParameter(query, gl.QUERY_RESULT_AVAILABLE)) break;
      await nextFrame();
    }
    const available = gl.getQueryParameter(query, gl.QUERY_RESULT_AVAILABLE);
    const disjoint = gl.getParameter(ext.GPU_DISJOINT_EXT);
    if (available && !disjoint) gpuMs = gl.getQueryParameter(query, gl.QUERY_RESULT) / 1e6;
    gl.deleteQuery(query);
  }
  return { wallMs, gpuMs };
}

function loadScene(url) {
  return new Promise((resolve, reject) => new GLTFLoader().load(url, resolve, undefined,
    (error) => reject(new Error(`GLTFLoader could not load ${url}: ${error}`))));
}

function named(root, name) {
  const node = root.getObjectByName(name);
  if (!node) throw new Error(`the exported scene has no node named ${name}`);
  return node;
}

async function run(config) {
  const { width, height } = config.camera;
  const canvas = document.createElement("canvas");
  canvas.width = width;
  canvas.height = height;
  document.body.appendChild(canvas);
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
  // Linear radiance out: no tone mapping, no sRGB encoding.
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  renderer.setClearColor(0x000000, 1);
  renderer.shadowMap.enabled = config.shadows;
  const gl = renderer.getContext();
  const offered = gl.getSupportedExtensions();
  const floatTargets = renderer.extensions.has("EXT_color_buffer_float");
  if (!floatTargets) throw new Error("WebGL2 without EXT_color_buffer_float: no float render targets");
  const timerExt = offered.includes(TIMER_EXTENSION) ? gl.getExtension(TIMER_EXTENSION) : null;

  const gltf = await loadScene(config.glb);
  const world = new THREE.Scene();
  const root = gltf.scene;
  root.position.fromArray(config.offset);
  world.add(root);
  root.updateMatrixWorld(true);

  // The component: its group stays at the origin (its update resets the group's world
  // matrix to the identity, and its plane is the group's y = 0: the receiver).
  const options = config.caustics;
  const objects = config.objects.map((name) => named(root, name));
  for (const node of objects) node.traverse((o) => { o.castShadow = config.shadows; });
  const component = (ior) => {
    const made = Caustics(renderer, {
      frames: 1, // drei's default: the caustic is computed once, on the first update
      causticsOnly: false,
      ior,
      backside: options.backside,
      backsideIOR: options.backsideIOR,
      worldRadius: options.worldRadius,
      intensity: options.intensity,
      color: new THREE.Color().setRGB(...options.color, THREE.LinearSRGBColorSpace),
      resolution: options.resolution,
      lightSource: new THREE.Vector3().fromArray(options.lightSource),
      near: options.near,
    });
    for (const node of objects) made.scene.attach(node); // keeps its world placement
    return made;
  };
  const dispose = (made) => {
    for (const t of [made.normalTarget, made.normalTargetB, made.causticsTarget,
      made.causticsTargetB]) t.dispose();
  };

  // Receivers: Lambertian, as the harness's (glTF's roughness-1 PBR material keeps a
  // specular lobe of F0 = 0.04).
  config.receivers.forEach((name, i) => {
    const node = named(root, name);
    node.material = new THREE.MeshLambertMaterial({
      color: new THREE.Color().setRGB(...config.albedo[i], THREE.LinearSRGBColorSpace),
    });
    node.receiveShadow = config.shadows;
  });

  // The light: intensity x colour is the irradiance in W/m^2 (read 1 lx as 1 W/m^2).
  let light = null;
  root.traverse((o) => { if (o.isDirectionalLight) light = o; });
  if (!light) throw new Error("the exported scene has no directional light");
  if (!config.directLighting) light.intensity = 0;
  const box = new THREE.Box3().setFromObject(root);
  for (const node of objects) box.expandByObject(node);
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  const toLight = new THREE.Vector3().fromArray(options.lightSource).normalize();
  // Shadow camera: the light's rays through the scene's bounding sphere.
  world.attach(light);
  light.position.copy(sphere.center).addScaledVector(toLight, 2 * sphere.radius);
  light.target.position.copy(sphere.center);
  world.add(light.target);
  light.castShadow = config.shadows;
  Object.assign(light.shadow.camera, { left: -sphere.radius, right: sphere.radius,
    top: sphere.radius, bottom: -sphere.radius, near: 0, far: 4 * sphere.radius });
  light.shadow.mapSize.set(2048, 2048);
  light.shadow.camera.updateProjectionMatrix();

  const camera = named(root, "camera");
  if (!camera.isPerspectiveCamera) throw new Error("the exported node camera is not a perspective camera");
  camera.far = camera.getWorldPosition(new THREE.Vector3()).distanceTo(sphere.center)
    + 2 * sphere.radius;
  camera.aspect = width / height;
  camera.updateProjectionMatrix();

  const colorTarget = new THREE.WebGLRenderTarget(width, height, {
    type: THREE.FloatType, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
    depthBuffer: true,
  });
  const res = options.resolution;
  const front = [];
  const back = [];
  const timings = { caustics: [], camera: [] };
  let timer = timerExt ? "gpu" : "wall";
  const clock = (t) => {
    if (t.gpuMs === null) timer = "wall";
    return t;
  };
  const pixels = new Float32Array(res * res * 4);
  const texel = new Float32Array(4);
  const red = new Float32Array(res * res);
  const readRed = (target) => {
    // The component writes vec3(caustic): R = G = B; keep R.
    renderer.readRenderTargetPixels(target, 0, 0, res, res, pixels);
    for (let i = 0; i < red.length; i++) red[i] = pixels[4 * i];
    return base64(red);
  };
  // Per pass (IOR), a fresh component read after its first update, as drei renders
  // with frames = 1. Its update is not repeatable as it stands: it reuses a matrix
  // whose translation the previous update left behind when it places the far plane
  // (far differs from the second update on; `farAfterRepeats` shows it), so the
  // timed repeats run on a second instance, which is then discarded.
  let shown = null;
  const lightCameras = [];
  const farAfterRepeats = [];
  for (const pass of config.passes) {
    if (shown) {
      world.remove(shown.group);
      dispose(shown);
    }
    shown = component(pass.ior);
    shown.update();
    const cam = shown.helper.camera;
    lightCameras.push({
      projection: cam.projectionMatrix.elements.slice(),
      view: cam.matrixWorldInverse.elements.slice(),
      near: cam.near, far: cam.far, left: cam.left, right: cam.right,
      top: cam.top, bottom: cam.bottom,
    });
    front.push(readRed(shown.causticsTarget));
    back.push(options.backside ? readRed(shown.causticsTargetB) : null);
    const timed = component(pass.ior);
    timed.params.frames = Infinity; // update on every call
    timed.update(); // warm-up
    const times = [];
    for (let i = 0; i < config.repeats; i++) {
      times.push(clock(await timeWork(gl, timerExt, () => timed.update(),
        () => renderer.readRenderTargetPixels(timed.causticsTarget, 0, 0, 1, 1, texel))));
    }
    timings.caustics.push(times);
    farAfterRepeats.push(timed.helper.camera.far);
    dispose(timed);
    for (const node of objects) shown.scene.attach(node);
  }
  world.add(shown.group);
  // The projected caustic lies on the receiver: draw it just in front of it (a
  // depth offset, not a move) so the two coplanar surfaces do not z-fight.
  const plane = shown.group.getObjectByName("caustics_plane");
  Object.assign(plane.material, { polygonOffset: true, polygonOffsetFactor: -1,
    polygonOffsetUnits: -4 });
  // The camera image with the last pass's caustic texture on the receiver (with one
  // IOR per channel, that IOR's caustic in every channel: the component has one).
  const draw = () => {
    renderer.setRenderTarget(colorTarget);
    renderer.render(world, camera);
    renderer.setRenderTarget(null);
  };
  draw();
  for (let i = 0; i < config.repeats; i++) {
    timings.camera.push(clock(await timeWork(gl, timerExt, draw,
      () => renderer.readRenderTargetPixels(colorTarget, 0, 0, 1, 1, texel))));
  }
  const image = new Float32Array(width * height * 4);
  renderer.readRenderTargetPixels(colorTarget, 0, 0, width, height, image);

  const pick = (list, key) => median(list.map((t) => t[key] ?? NaN));
  return {
    front,
    back,
    resolution: res,
    lightCameras,
    farAfterRepeats,
    plane: { position: plane.position.toArray(), scale: plane.scale.toArray() },
    camera: base64(image),
    width, height,
    timings: {
      caustics_gpu_ms: timings.caustics.map((l) => pick(l, "gpuMs")),
      caustics_wall_ms: timings.caustics.map((l) => pick(l, "wallMs")),
      camera_gpu_ms: pick(timings.camera, "gpuMs"),
      camera_wall_ms: pick(timings.camera, "wallMs"),
    },
    timer,
    repeats: config.repeats,
    causticsType: shown.causticsTarget.texture.type === THREE.FloatType ? "float32" : "float16",
    webgl: {
      renderer: (() => {
        const info = gl.getExtension("WEBGL_debug_renderer_info");
        return info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
      })(),
      timerQuery: Boolean(timerExt),
      extensions: offered,
    },
    three: THREE.REVISION,
  };
}

window.dreiCaustics = { run };
