// ist view — the page's script (an ES module, no build step, no framework).
//
// What it shows: body A fixed at the identity, body B at the pose the server's 1 kHz loop
// reports (`pose_b`), and over them the loop's answers: the closest points (a line), the
// contact patches (discs), force and torque (arrows), the loop's timing (numbers and a
// chart), optionally the inner spheres of one body at one level of its tree, and in
// contact-map mode both surfaces coloured by their gap to the other body.
//
// How B moves: a TransformControls gizmo on a proxy object stands for B's *target* pose
// (`target_b`); dragging it, Shift-dragging on the canvas, or typing a pose POSTs
// /api/pose. The server owns the truth: the page draws B where the state says (in haptic
// mode the coupled tool, which stops at A, while the gizmo is the device).
//
// The HTTP API (JSON unless said; poses are [tx, ty, tz, qw, qx, qy, qz], p' = R(q)·p + t,
// B's pose in A's frame; points, normals, force, torque in A's frame = the world here):
//   GET  /api/info, /api/state, /api/events (SSE of the state), /api/spheres (binary),
//   GET  /api/mesh (binary), POST /api/pose, /api/mode, /api/motion;
//   contact map: GET /api/contact-map, /api/contact-map/bands (binary), POST /api/contact-map.
//
// For the end-to-end test the page exposes `window.__ist` (see `ist` below).

import * as THREE from 'three';
import { OrbitControls } from '/assets/vendor/OrbitControls.js';
import { TransformControls } from '/assets/vendor/TransformControls.js';

// ---------------------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------------------

const $ = (id) => document.getElementById(id);

/** JSON request; throws an Error carrying the server's `{"error": …}` message on 4xx/5xx. */
async function api(path, body) {
  const init = body === undefined
    ? {}
    : { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) };
  const res = await fetch(path, init);
  if (!res.ok) {
    let msg = `${res.status} ${res.statusText}`;
    try { msg = (await res.json()).error || msg; } catch { /* not JSON */ }
    throw new Error(`${init.method || 'GET'} ${path}: ${msg}`);
  }
  return res.json();
}

/** Binary GET; resolves to null on 404 (e.g. a body without a mesh). */
async function apiBinary(path) {
  const res = await fetch(path);
  if (res.status === 404) return null;
  if (!res.ok) throw new Error(`GET ${path}: ${res.status} ${res.statusText}`);
  return res.arrayBuffer();
}

let errorTimer = 0;
/** Shows an error in the panel for a few seconds (and in the console). */
function showError(err) {
  console.error(err);
  const el = $('error');
  el.textContent = String(err && err.message ? err.message : err);
  el.hidden = false;
  clearTimeout(errorTimer);
  errorTimer = setTimeout(() => { el.hidden = true; }, 6000);
}

/** A number for the panel: fixed digits for ordinary sizes, exponent for tiny ones. */
function num(x, digits = 4) {
  if (x === null || x === undefined || !Number.isFinite(x)) return '—';
  if (x === 0) return '0';
  const a = Math.abs(x);
  if (a < 1e-3 || a >= 1e6) return x.toExponential(2);
  return String(Number(x.toPrecision(digits)));
}

const v3 = (a) => new THREE.Vector3(a[0], a[1], a[2]);
const len3 = (a) => Math.hypot(a[0], a[1], a[2]);

/** Pose [tx,ty,tz,qw,qx,qy,qz] → (position, quaternion). three's Quaternion is (x,y,z,w). */
function poseParts(p) {
  const q = new THREE.Quaternion(p[4], p[5], p[6], p[3]);
  if (q.lengthSq() > 0) q.normalize(); else q.identity();
  return { t: new THREE.Vector3(p[0], p[1], p[2]), q };
}

/** Sets a (matrixAutoUpdate = false) object's matrix to the pose. */
function setObjectPose(obj, p) {
  const { t, q } = poseParts(p);
  obj.matrix.compose(t, q, new THREE.Vector3(1, 1, 1));
  obj.matrixWorldNeedsUpdate = true;
}

function posesClose(p, q, eps = 1e-6) {
  if (!p || !q) return false;
  for (let i = 0; i < 7; i++) if (Math.abs(p[i] - q[i]) > eps) return false;
  return true;
}

/** Parses "tx ty tz qw qx qy qz" (spaces, commas or brackets) into 7 numbers, or throws. */
function parsePose(text) {
  const parts = text.replace(/[[\](),;]/g, ' ').trim().split(/\s+/).filter(Boolean).map(Number);
  if (parts.length !== 7 || parts.some((x) => !Number.isFinite(x))) {
    throw new Error('a pose is 7 numbers: tx ty tz qw qx qy qz');
  }
  return parts;
}

const formatPose = (p) => p.map((x, i) => (i < 3 ? x.toFixed(3) : x.toFixed(5))).join(' ');

/**
 * POSTs to one endpoint with at most one request in flight and at most one every
 * `minGapMs`: a newer body replaces a queued one (only the latest pose matters while
 * dragging). `send` resolves with the answer to the request that carried this body or a
 * later one.
 */
class LatestOnlyPoster {
  constructor(path, minGapMs, onAnswer) {
    this.path = path;
    this.minGapMs = minGapMs;
    this.onAnswer = onAnswer;
    this.inFlight = false;
    this.queued = null; // { body, waiters: [{resolve, reject}] }
    this.lastAt = -Infinity;
    this.timer = 0;
  }

  send(body) {
    return new Promise((resolve, reject) => {
      const waiters = this.queued ? this.queued.waiters : [];
      waiters.push({ resolve, reject });
      this.queued = { body, waiters };
      this.pump();
    });
  }

  pump() {
    if (this.inFlight || !this.queued || this.timer) return;
    const wait = this.minGapMs - (performance.now() - this.lastAt);
    if (wait > 0) {
      this.timer = setTimeout(() => { this.timer = 0; this.pump(); }, wait);
      return;
    }
    const { body, waiters } = this.queued;
    this.queued = null;
    this.inFlight = true;
    this.lastAt = performance.now();
    api(this.path, body)
      .then((answer) => {
        this.onAnswer(body, answer);
        waiters.forEach((w) => w.resolve(answer));
      })
      .catch((err) => {
        showError(err);
        waiters.forEach((w) => w.reject(err));
      })
      .finally(() => {
        this.inFlight = false;
        this.pump();
      });
  }
}

// ---------------------------------------------------------------------------------------
// Test hooks
// ---------------------------------------------------------------------------------------

/** What the end-to-end test reads and drives. */
const ist = {
  ready: false, // true once a frame has rendered with both bodies loaded and a state
  frames: 0, // rendered frames
  state: null, // the latest state from the server
  info: null, // /api/info
  spheres: { shown: false, body: null, level: null, count: 0, loading: false },
  screenOfB: () => screenOf(bodyCentreWorld('b')),
  screenOfA: () => screenOf(bodyCentreWorld('a')),
  /** Sends B's pose; resolves with the contact quantities the page shows for it (the
   *  answer's sphere distance and penetration, as `contactOfAnswer` reads them). */
  setPose: (p7) => {
    setProxyFromPose(p7);
    return sendPose(p7).then((a) => a && contactOfAnswer(a));
  },
  /** Contact-map mode: whether it is available and on, the server's latest map (`seq`,
   *  `status`, `rate_hz`, `compute_ms`), the map the meshes show (`shownSeq`, its `pose`,
   *  vertices per band `counts.a` / `counts.b`), colour updates applied and the last one's
   *  time to write the colours (`paint_ms`), which bodies are shown (`shown`), the per-tooth
   *  list shown, and whether the meshes' materials use vertex colours. */
  contactMap: {
    available: false, on: false, status: null, seq: 0, shownSeq: 0, pose: null, counts: null,
    updates: 0, paint_ms: null, teeth: null, rate_hz: 0, compute_ms: null, shown: 'both',
    vertexColors: () => ['a', 'b'].map((n) => !!(bodies[n].material && bodies[n].material.vertexColors)),
    legendRows: () => document.querySelectorAll('#cm-legend tr').length,
    overlayShown: () => !$('cm-overlay').hidden,
  },
  /** What the overlays show now (visible patch discs, arrows, closest-point line). */
  overlays: () => ({
    discs: discs.filter((d) => d.visible).length,
    force: forceArrow.visible,
    torque: torqueArrow.visible,
    device: deviceArrow.visible,
    ghost: ghostB.visible,
    line: distLine.visible,
  }),
};
window.__ist = ist;

// ---------------------------------------------------------------------------------------
// Scene
// ---------------------------------------------------------------------------------------

const renderer = new THREE.WebGLRenderer({ antialias: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.setClearColor(0x1d2026);
const canvas = renderer.domElement;
canvas.id = 'view';
document.body.prepend(canvas);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 0.1, 10000);
// The demo's teeth (and the jaw data) stand along +z: orbit about z. Must be set before
// OrbitControls is made (it takes the up vector once, at construction).
camera.up.set(0, 0, 1);
scene.add(camera);

scene.add(new THREE.HemisphereLight(0xffffff, 0x3a3f4a, 1.6));
const headLight = new THREE.DirectionalLight(0xffffff, 1.6); // follows the camera
headLight.position.set(0.3, 0.6, 1);
camera.add(headLight);

const orbit = new OrbitControls(camera, canvas);
orbit.enableDamping = false; // no inertia: the view stops when the mouse does

/** Body A: fixed, at the identity. */
const bodyA = new THREE.Group();
/** Body B: its matrix is the drawn pose (`pose_b`). */
const bodyB = new THREE.Group();
bodyB.matrixAutoUpdate = false;
/** Haptic mode: a faint copy of B at the device pose (`target_b`). */
const ghostB = new THREE.Group();
ghostB.matrixAutoUpdate = false;
ghostB.visible = false;
scene.add(bodyA, bodyB, ghostB);
const bodyGroup = { a: bodyA, b: bodyB };

// Per body: bounding box (model frame), mesh (or null), its material.
const bodies = {
  a: { box: new THREE.Box3(), mesh: null, material: null, color: 0xe9dfc6 },
  b: { box: new THREE.Box3(), mesh: null, material: null, color: 0x8fbde6 },
};

/** B's bounding-box centre in its model frame: the gizmo's pivot. */
const pivotB = new THREE.Vector3();

/**
 * The gizmo's object: B's target pose, placed at B's centre (so that the rotate rings turn
 * B about its middle, not about a model origin that may lie far from the bone):
 * proxy = pose ∘ translate(pivotB), i.e. proxy.position = R·pivot + t, proxy.quaternion = q.
 */
const proxy = new THREE.Object3D();
scene.add(proxy);

function setProxyFromPose(p) {
  const { t, q } = poseParts(p);
  proxy.quaternion.copy(q);
  proxy.position.copy(pivotB).applyQuaternion(q).add(t);
  proxy.updateMatrixWorld();
  updatePoseInput();
}

function poseFromProxy() {
  const q = proxy.quaternion.clone().normalize();
  const t = proxy.position.clone().sub(pivotB.clone().applyQuaternion(q));
  return [t.x, t.y, t.z, q.w, q.x, q.y, q.z];
}

const gizmo = new TransformControls(camera, canvas);
gizmo.setSize(0.8);
gizmo.attach(proxy);
scene.add(gizmo.getHelper());
gizmo.addEventListener('dragging-changed', (e) => {
  orbit.enabled = !e.value; // the gizmo's drag must not also orbit the view
  dragging = e.value;
});
gizmo.addEventListener('objectChange', () => {
  if (!gizmo.dragging) return;
  updatePoseInput();
  sendPose(poseFromProxy());
});

/** True while the user drags B (gizmo or Shift-drag): the server's target must not
 *  snap the proxy back meanwhile. */
let dragging = false;

// ---------------------------------------------------------------------------------------
// Overlays (drawn over the bodies: depthTest off, since contacts lie inside them)
// ---------------------------------------------------------------------------------------

const overlayOrder = 10;
function overlay(obj) {
  obj.renderOrder = overlayOrder;
  obj.traverse((o) => {
    if (o.material) { o.material.depthTest = false; o.material.transparent = true; }
    o.renderOrder = overlayOrder;
  });
  scene.add(obj);
  return obj;
}

// Closest points: a line and a dot at each end (shown while apart).
const distLine = overlay(new THREE.Line(
  new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]),
  new THREE.LineBasicMaterial({ color: 0xffe24a }),
));
distLine.frustumCulled = false; // its points change every state; its bounding sphere does not
const dotGeo = new THREE.SphereGeometry(1, 12, 8);
const dotA = overlay(new THREE.Mesh(dotGeo, new THREE.MeshBasicMaterial({ color: 0xffe24a })));
const dotB = overlay(new THREE.Mesh(dotGeo, new THREE.MeshBasicMaterial({ color: 0xffe24a })));

// Contact patches: a pool of discs, one per patch, facing the patch normal.
const discGeo = new THREE.CircleGeometry(1, 28);
const discs = [];
function disc(i) {
  while (discs.length <= i) {
    const m = overlay(new THREE.Mesh(discGeo, new THREE.MeshBasicMaterial({
      color: 0xff5030, side: THREE.DoubleSide, opacity: 0.8,
    })));
    m.visible = false;
    discs.push(m);
  }
  return discs[i];
}

// Force on B (at the patches' centroid), torque on B (at B's centre; the library gives it
// about B's centre of mass), and in haptic mode the device force (at the device pose).
function arrow(color) {
  const a = overlay(new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 1, color));
  a.visible = false;
  return a;
}
const forceArrow = arrow(0xff3b3b);
const torqueArrow = arrow(0x3bc8ff);
const deviceArrow = arrow(0xffa020);

/** Length scales for the arrows. Forces here span decades (a graze gives 1e-4, a deep
 *  push 1e2), so an arrow's length is logarithmic around the recent typical magnitude
 *  (an average of log10 m over a few seconds): typical → 0.6 of the longest arrow, 100×
 *  more → the longest, 100× less → 0.2, never shorter than 0.12 nor longer than 1. The
 *  panel gives the numbers; the arrow shows direction and "weak or strong lately". */
const refLog = { force: null, torque: null, device: null };

/** Bodies' size (diagonal of the union of boxes), set when framing: scales the overlays. */
let sceneSize = 10;

/** Sets arrow `a` to show `vec`: its tail at `at`, or with `tipAt` its tip there. */
function placeArrow(a, key, vec, at, tipAt = false) {
  const m = vec ? len3(vec) : 0;
  if (!(m > 1e-12)) { a.visible = false; return; }
  const lg = Math.log10(m);
  refLog[key] = refLog[key] === null ? lg : refLog[key] + (lg - refLog[key]) * 0.02;
  const frac = THREE.MathUtils.clamp(0.6 + 0.2 * (lg - refLog[key]), 0.12, 1);
  const len = sceneSize * 0.35 * frac;
  const dir = v3(vec).divideScalar(m);
  a.position.copy(at);
  if (tipAt) a.position.addScaledVector(dir, -len);
  a.setDirection(dir);
  a.setLength(len, len * 0.22, len * 0.12);
  a.visible = true;
}

// ---------------------------------------------------------------------------------------
// Inner spheres: ONE InstancedMesh per layer (x, y, z, r per sphere, in the body's frame)
// ---------------------------------------------------------------------------------------

class SphereLayer {
  constructor(name) {
    this.name = name;
    this.mesh = null;
    this.body = null;
    this.level = null;
    this.count = 0;
    this.serial = 0; // discards answers to requests a newer one replaced
  }

  /** Fetches the spheres of `body` at `level` and replaces the layer's mesh. */
  async load(body, level) {
    if (this.mesh && this.body === body && this.level === level) return;
    const serial = ++this.serial;
    const buf = await apiBinary(`/api/spheres?body=${body}&level=${level}`);
    if (serial !== this.serial) return; // a newer request won
    if (!buf || buf.byteLength % 16 !== 0) throw new Error(`bad sphere data for ${body} level ${level}`);
    const s = new Float32Array(buf);
    const n = s.length / 4;
    // 20 triangles a sphere above 40k spheres, else 80: a 150k-sphere level stays drawable.
    const geo = new THREE.IcosahedronGeometry(1, n > 40000 ? 0 : 1);
    const mat = new THREE.MeshPhongMaterial({ color: 0xffffff, shininess: 20 });
    const mesh = new THREE.InstancedMesh(geo, mat, Math.max(n, 1));
    mesh.count = n;
    mesh.frustumCulled = false; // the instances' extent is not the geometry's
    const m = new THREE.Matrix4();
    const c = new THREE.Color();
    const base = new THREE.Color(body === 'a' ? 0xf0a040 : 0x40c0a0);
    let rmax = 0;
    for (let i = 0; i < n; i++) rmax = Math.max(rmax, s[4 * i + 3]);
    for (let i = 0; i < n; i++) {
      const r = s[4 * i + 3];
      m.makeScale(r, r, r).setPosition(s[4 * i], s[4 * i + 1], s[4 * i + 2]);
      mesh.setMatrixAt(i, m);
      // Big spheres light, small ones dark: the packing's structure reads at a glance.
      c.copy(base).multiplyScalar(0.45 + 0.55 * (rmax > 0 ? r / rmax : 1));
      mesh.setColorAt(i, c);
    }
    mesh.instanceMatrix.needsUpdate = true;
    if (mesh.instanceColor) mesh.instanceColor.needsUpdate = true;
    this.dispose();
    this.mesh = mesh;
    this.body = body;
    this.level = level;
    this.count = n;
    bodyGroup[body].add(mesh); // B's spheres follow B's pose
  }

  setVisible(v) { if (this.mesh) this.mesh.visible = v; }

  dispose() {
    if (!this.mesh) return;
    this.mesh.parent?.remove(this.mesh);
    this.mesh.geometry.dispose();
    this.mesh.material.dispose();
    this.mesh.dispose();
    this.mesh = null;
    this.count = 0;
  }
}

/** The spheres the user looks at (panel: show, body, level). */
const inspectLayer = new SphereLayer('inspect');
/** The picture of a body that has no mesh: its leaves. */
const standIn = { a: null, b: null };

// ---------------------------------------------------------------------------------------
// Loading: info, meshes, stand-in spheres
// ---------------------------------------------------------------------------------------

async function loadMesh(name) {
  const buf = await apiBinary(`/api/mesh?body=${name}`);
  if (!buf) return null;
  const dv = new DataView(buf);
  const nv = dv.getUint32(0, true);
  const nt = dv.getUint32(4, true);
  if (buf.byteLength !== 8 + nv * 12 + nt * 12) throw new Error(`bad mesh data for ${name}`);
  const geo = new THREE.BufferGeometry();
  geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(buf, 8, nv * 3), 3));
  geo.setIndex(new THREE.BufferAttribute(new Uint32Array(buf, 8 + nv * 12, nt * 3), 1));
  geo.computeVertexNormals();
  geo.computeBoundingBox();
  return geo;
}

async function loadBody(name) {
  const info = ist.info.bodies[name];
  const b = bodies[name];
  b.box.set(v3(info.bbox_min), v3(info.bbox_max));
  const geo = info.has_mesh ? await loadMesh(name) : null;
  if (geo) {
    b.material = new THREE.MeshPhongMaterial({ color: b.color, shininess: 40, side: THREE.DoubleSide });
    b.mesh = new THREE.Mesh(geo, b.material);
    bodyGroup[name].add(b.mesh);
  } else {
    // No mesh: the leaves are the picture.
    standIn[name] = new SphereLayer(`stand-in ${name}`);
    await standIn[name].load(name, Math.max(0, info.levels - 1));
  }
  if (name === 'b') {
    b.box.getCenter(pivotB);
    // The ghost: B's mesh, faint, plus B's box outline (thin, readable over anything).
    if (b.mesh) {
      ghostB.add(new THREE.Mesh(b.mesh.geometry, new THREE.MeshBasicMaterial({
        color: 0xc0d8ff, transparent: true, opacity: 0.18, depthWrite: false,
      })));
    }
    ghostB.add(new THREE.Box3Helper(b.box.clone(), 0xc0d8ff));
  }
}

/** The splint (`ist view --splint`): a resin-coloured solid fixed in A's frame, with a
 *  checkbox to hide it. */
async function loadSplint(info) {
  if (!info.splint) return;
  const geo = await loadMesh('splint');
  if (!geo) return;
  const mesh = new THREE.Mesh(geo, new THREE.MeshPhongMaterial({
    color: 0x8fd0c8, shininess: 60, transparent: true, opacity: 0.8, side: THREE.DoubleSide,
  }));
  mesh.name = 'splint';
  bodyA.add(mesh);
  $('splint-panel').hidden = false;
  $('show-splint').addEventListener('change', (e) => { mesh.visible = e.target.checked; });
}

// ---------------------------------------------------------------------------------------
// Camera framing
// ---------------------------------------------------------------------------------------

/** A body's box centre in the world (B's at its drawn pose). */
function bodyCentreWorld(name) {
  const c = bodies[name].box.getCenter(new THREE.Vector3());
  if (name === 'b') { bodyB.updateMatrixWorld(); c.applyMatrix4(bodyB.matrixWorld); }
  return c;
}

/** A world point in page CSS pixels. */
function screenOf(p) {
  camera.updateMatrixWorld();
  const ndc = p.clone().project(camera);
  const r = canvas.getBoundingClientRect();
  return [r.left + (ndc.x + 1) / 2 * r.width, r.top + (1 - ndc.y) / 2 * r.height];
}

/** Points the camera at the union of A's box and B's box at its drawn pose. */
function frameBodies() {
  bodyB.updateMatrixWorld();
  const box = bodies.a.box.clone().union(bodies.b.box.clone().applyMatrix4(bodyB.matrixWorld));
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  sceneSize = radius * 2;
  // Fit the sphere around the boxes into the free part of the view (vertical field of
  // view, or the horizontal one of the free part when that is narrower).
  const fov = THREE.MathUtils.degToRad(camera.fov);
  const hfov = 2 * Math.atan(Math.tan(fov / 2) * freeWidth() / window.innerHeight);
  const dist = radius / Math.sin(Math.min(fov, hfov) / 2) * 1.05;
  const dir = new THREE.Vector3(0.55, -1, 0.45).normalize(); // front, right, a little above
  camera.position.copy(centre).addScaledVector(dir, dist);
  camera.near = dist / 100;
  camera.far = dist * 100;
  camera.updateProjectionMatrix();
  orbit.target.copy(centre);
  orbit.update();
  dotA.scale.setScalar(sceneSize * 0.006);
  dotB.scale.setScalar(sceneSize * 0.006);
}

// ---------------------------------------------------------------------------------------
// Applying the server's answers
// ---------------------------------------------------------------------------------------

/** The last pose this page sent, and when: the state stream lags it by up to a frame or
 *  two, and a stale state must not drag the proxy (and B) back. */
let lastSent = null;

/** Sends B's target pose (throttled, one request in flight, latest wins). */
const posePoster = new LatestOnlyPoster('/api/pose', 16, (body, answer) => {
  // In free mode B is at the target, so the answer is what to show now; in haptic and
  // motion modes the state stream says where B really is.
  const mode = currentMode();
  if (!mode || mode === 'free') {
    showPose(body.pose_b);
    showContact(contactOfAnswer(answer));
  }
});

/** A /api/pose answer (each query in the form `ist query --json` prints) as the contact
 *  quantities a state holds: the sphere distance and its closest points, the penetration's
 *  volume, depth, force, torque on B and patches. */
function contactOfAnswer(a) {
  const d = a.distance, p = a.penetration;
  return {
    distance: d.distance, contact: d.contact, point_a: d.point_a, point_b: d.point_b,
    volume: p.volume, max_depth: p.max_depth, force: p.force, torque: p.torque_b,
    patches: p.patches,
  };
}
function sendPose(p) {
  lastSent = { pose: p, at: performance.now() };
  leaveMotionMode();
  return posePoster.send({ pose_b: p });
}

/** The mode this page last asked for (for a second: until the state stream shows it),
 *  else the state's. */
let modeAsked = null; // { mode, at }
function currentMode() {
  if (modeAsked && performance.now() - modeAsked.at < 1000) return modeAsked.mode;
  return ist.state ? ist.state.mode : null;
}
function setMode(mode) {
  modeAsked = { mode, at: performance.now() };
  return api('/api/mode', { mode });
}

/** Moving B by hand while the motion drives it would do nothing (the loop follows the
 *  motion): the first hand move switches the server to free mode. */
let leavingMotion = false;
function leaveMotionMode() {
  if (leavingMotion || currentMode() !== 'motion') return;
  leavingMotion = true;
  setMode('free')
    .catch(showError)
    .finally(() => { setTimeout(() => { leavingMotion = false; }, 200); });
}

/** Draws B at `p`. */
function showPose(p) {
  setObjectPose(bodyB, p);
}

/** The contact quantities (a state or a /api/pose answer): overlays and panel numbers. */
function showContact(s) {
  // Panel.
  $('distance').textContent = `${num(s.distance)} mm`;
  // A state says whether its distance is the meshes' (refined) or the sphere packings'.
  if (s.distance_refined !== undefined) {
    $('distance-label').textContent = s.distance_refined ? 'distance (meshes)' : 'distance (spheres)';
  }
  // The meshes' own contact (`--contact mesh`): their exact volume and the patches' mean depth.
  const of = s.contact_source === 'mesh' ? ' (meshes)' : '';
  $('volume').textContent = `${num(s.volume)} mm³${of}`;
  $('max-depth').textContent = `${num(s.max_depth)} mm${of}`;
  $('force').textContent = `${num(len3(s.force))} N`;
  $('force').title = `(${s.force.map((x) => num(x, 3)).join(', ')})`;
  $('torque').textContent = `${num(len3(s.torque))} N·mm`;
  $('torque').title = `(${s.torque.map((x) => num(x, 3)).join(', ')})`;
  $('patch-count').textContent = String(s.patches.length);
  const contact = $('contact');
  contact.classList.toggle('on', !!s.contact);
  contact.textContent = s.contact ? 'contact' : 'apart';

  // Closest points, while apart.
  const apart = !s.contact && Number.isFinite(s.distance);
  distLine.visible = dotA.visible = dotB.visible = apart;
  if (apart) {
    const pa = v3(s.point_a), pb = v3(s.point_b);
    distLine.geometry.setFromPoints([pa, pb]);
    dotA.position.copy(pa);
    dotB.position.copy(pb);
  }

  // Patches: disc area ~ volume^(2/3) (radius = cbrt(volume)), colour from yellow
  // (shallow) to red (the deepest of this state).
  let wsum = 0;
  const centroid = new THREE.Vector3();
  const dmax = Math.max(s.max_depth || 0, ...s.patches.map((p) => p.depth), 1e-12);
  s.patches.forEach((p, i) => {
    const d = disc(i);
    const r = THREE.MathUtils.clamp(Math.cbrt(Math.max(p.volume, 0)), sceneSize * 0.01, sceneSize * 0.15);
    d.position.copy(v3(p.point));
    const n = v3(p.normal);
    if (n.lengthSq() > 0) d.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), n.normalize());
    d.scale.setScalar(r);
    d.material.color.setHSL(0.16 * (1 - Math.min(p.depth / dmax, 1)), 1, 0.55);
    d.visible = true;
    centroid.addScaledVector(v3(p.point), p.volume);
    wsum += p.volume;
  });
  for (let i = s.patches.length; i < discs.length; i++) discs[i].visible = false;

  // Arrows: the force on B pushing at the patches' (volume-weighted) centroid — its tip
  // there, so that it reads as "A pushes B here" and stays clear of B's gizmo — else at
  // B's centre; the torque on B (about its centre of mass) at B's centre.
  const centreB = bodyCentreWorld('b');
  if (wsum > 0) placeArrow(forceArrow, 'force', s.force, centroid.divideScalar(wsum), true);
  else placeArrow(forceArrow, 'force', s.force, centreB);
  placeArrow(torqueArrow, 'torque', s.torque, centreB);
  if (ist.contactMap.shown !== 'both') hideContactOverlays();
}

/** With one body shown alone (contact map), its surface is the picture: no overlays. */
function hideContactOverlays() {
  distLine.visible = dotA.visible = dotB.visible = false;
  forceArrow.visible = torqueArrow.visible = false;
  for (const d of discs) d.visible = false;
}

/** Everything else in a state: loop numbers, chart, mode, motion, haptic ghost. */
function showLoop(s) {
  const l = s.loop;
  if (l) {
    $('rate').textContent = `${num(l.rate_hz, 5)} Hz`;
    $('tick').textContent = `${num(l.tick_us, 3)} µs`;
    $('tick').title = `p99 ${num(l.tick_us_p99, 3)} µs, max ${num(l.tick_us_max, 3)} µs, ${l.ticks} ticks`;
    $('over').textContent = `${l.over_1ms} of ${l.ticks}`;
    // Haptic mode: the servo runs at the loop's rate, the collision thread at its own.
    $('collision-row').hidden = s.mode !== 'haptic';
    $('collision').textContent = `${num(l.collision_rate_hz, 5)} Hz`;
    $('collision').title = `contact models per second; the one in use is ${num(l.model_age_us, 3)} µs old`;
    drawTickChart(l);
  }
  const modeSel = $('mode');
  const mode = currentMode() || s.mode; // what was just asked for, not a state that predates it
  if (document.activeElement !== modeSel && modeSel.value !== mode) modeSel.value = mode;

  const haptic = s.mode === 'haptic';
  ghostB.visible = haptic;
  $('device-force-row').hidden = !haptic;
  if (haptic) {
    setObjectPose(ghostB, s.target_b);
    $('device-force').textContent = `${num(len3(s.device_force))} N`;
    ghostB.updateMatrixWorld();
    const at = bodies.b.box.getCenter(new THREE.Vector3()).applyMatrix4(ghostB.matrixWorld);
    placeArrow(deviceArrow, 'device', s.device_force, at);
  } else {
    deviceArrow.visible = false;
  }

  if (s.motion) showMotion(s.motion);
}

/** A state from the stream (or a poll). */
function applyState(s) {
  ist.state = s;
  lastStateAt = performance.now();
  // Right after this page sent a pose, the stream may still carry the previous target
  // (or, while leaving motion mode, the motion's): such a state would pull B (and the
  // proxy) back for a frame. Skip its pose and contact until the server's target catches
  // up (or a second has passed).
  const stale = lastSent && (s.mode === 'free' || leavingMotion)
    && performance.now() - lastSent.at < 1000 && !posesClose(s.target_b, lastSent.pose);
  if (!stale) {
    showPose(s.pose_b);
    showContact(s);
    if (!dragging) {
      const cur = poseFromProxy();
      if (!posesClose(cur, s.target_b, 1e-9)) setProxyFromPose(s.target_b);
    }
  }
  showLoop(s);
  syncContactMap(s.contact_map);
}

// ---------------------------------------------------------------------------------------
// Tick chart: the last ~240 tick times as bars, the 1 ms budget as a red line when in range
// ---------------------------------------------------------------------------------------

const chart = $('tick-chart');
const chartCtx = chart.getContext('2d');
let chartScale = 0; // µs at the top of the chart

/** Bars of the recent tick times. The scale follows the bulk of the ticks (twice their
 *  95th percentile), not the rare spike: a spike is clipped to the top and drawn orange
 *  (red when it missed the 1 ms budget), so that a single slow tick does not flatten
 *  the rest. The dashed line is the loop's p99 (over the last 1000 ticks), the red line
 *  the 1 ms budget when it is within the scale. */
function drawTickChart(l) {
  const h = l.history_us || [];
  const W = chart.width, H = chart.height, top = 12;
  const g = chartCtx;
  g.fillStyle = '#14161b';
  g.fillRect(0, 0, W, H);
  if (!h.length) return;
  const sorted = [...h].sort((x, y) => x - y);
  const p95 = sorted[Math.min(sorted.length - 1, Math.floor(sorted.length * 0.95))];
  const want = Math.max(2 * p95, (l.tick_us_p99 || 0) * 1.2, 2);
  // Grow at once, shrink gently: the bars do not jump with every state.
  chartScale = want > chartScale ? want : chartScale * 0.9 + want * 0.1;
  const yOf = (us) => H - Math.min(us / chartScale, 1) * (H - top);
  const bw = W / 240;
  for (let i = 0; i < h.length; i++) {
    const v = h[i];
    g.fillStyle = v > 1000 ? '#ff4d4d' : v > chartScale ? '#ffa64d' : '#6cc3ff';
    const y = yOf(v);
    g.fillRect(W - (h.length - i) * bw, y, Math.max(bw - 0.2, 0.6), H - y);
  }
  if (l.tick_us_p99 > 0 && l.tick_us_p99 < chartScale) {
    g.strokeStyle = '#e0e0e0'; g.setLineDash([3, 3]); g.beginPath();
    g.moveTo(0, yOf(l.tick_us_p99)); g.lineTo(W, yOf(l.tick_us_p99)); g.stroke(); g.setLineDash([]);
  }
  if (chartScale > 1000) {
    g.strokeStyle = '#ff4d4d'; g.beginPath(); g.moveTo(0, yOf(1000)); g.lineTo(W, yOf(1000)); g.stroke();
  }
  g.fillStyle = '#c8ccd4';
  g.font = '10px sans-serif';
  g.fillText(`${num(chartScale, 2)} µs`, 3, 10);
  g.textAlign = 'right';
  g.fillText(`p99 ${num(l.tick_us_p99, 3)} µs`, W - 3, 10);
  g.textAlign = 'left';
}

// ---------------------------------------------------------------------------------------
// Live state: server-sent events, falling back to polling
// ---------------------------------------------------------------------------------------

let pollTimer = 0;
function connect() {
  const es = new EventSource('/api/events');
  es.onopen = () => { $('conn').textContent = 'live'; $('conn').className = 'conn live'; };
  es.onmessage = (e) => {
    try { applyState(JSON.parse(e.data)); } catch (err) { showError(err); }
  };
  es.onerror = () => {
    // Poll /api/state instead, and try the stream again in a few seconds.
    es.close();
    $('conn').textContent = 'polling';
    $('conn').className = 'conn poll';
    startPolling();
    setTimeout(() => { stopPolling(); connect(); }, 5000);
  };
}
function startPolling() {
  if (pollTimer) return;
  const tick = async () => {
    try { applyState(await api('/api/state')); } catch (err) {
      $('conn').textContent = 'disconnected';
      $('conn').className = 'conn off';
    }
    if (pollTimer) pollTimer = setTimeout(tick, 100);
  };
  pollTimer = setTimeout(tick, 0);
}
function stopPolling() { clearTimeout(pollTimer); pollTimer = 0; }

// A stream that is open but silent (a proxy buffering it, say) raises no error: if no state
// came for two seconds, fetch one now and then.
let lastStateAt = 0;
setInterval(async () => {
  if (pollTimer || performance.now() - lastStateAt < 2000) return;
  try { applyState(await api('/api/state')); } catch { /* the panel shows the connection */ }
}, 1000);

// ---------------------------------------------------------------------------------------
// Panel controls
// ---------------------------------------------------------------------------------------

function updatePoseInput() {
  const el = $('pose-input');
  if (document.activeElement !== el) el.value = formatPose(poseFromProxy());
}

function setGizmoMode(m) {
  gizmo.setMode(m);
  $('gizmo-translate').classList.toggle('active', m === 'translate');
  $('gizmo-rotate').classList.toggle('active', m === 'rotate');
}

function setupPanel(info) {
  // Mode: only what the server offers.
  const modeSel = $('mode');
  for (const m of info.modes) modeSel.add(new Option(m, m));
  modeSel.addEventListener('change', async () => {
    try {
      await setMode(modeSel.value);
    } catch (err) {
      showError(err);
      modeAsked = null;
      if (ist.state) modeSel.value = ist.state.mode;
    }
    modeSel.blur();
  });

  // Moving B.
  $('gizmo-translate').addEventListener('click', () => setGizmoMode('translate'));
  $('gizmo-rotate').addEventListener('click', () => setGizmoMode('rotate'));
  const applyTyped = () => {
    try {
      const p = parsePose($('pose-input').value);
      setProxyFromPose(p);
      sendPose(p).catch(() => {}); // the poster already shows the error
    } catch (err) { showError(err); }
  };
  $('pose-apply').addEventListener('click', applyTyped);
  $('pose-input').addEventListener('keydown', (e) => { if (e.key === 'Enter') applyTyped(); });

  window.addEventListener('keydown', (e) => {
    if (e.target.closest && e.target.closest('input, select, textarea')) return;
    if (e.key === 't') setGizmoMode('translate');
    else if (e.key === 'r') setGizmoMode('rotate');
    else if (e.key === 'f') frameBodies();
  });

  // Motion.
  if (info.motion) {
    $('motion-panel').hidden = false;
    const tl = $('timeline');
    tl.max = String(info.motion.seconds);
    showMotion({ playing: false, t: 0, seconds: info.motion.seconds });
    $('play').addEventListener('click', async () => {
      const playing = !(ist.state && ist.state.motion && ist.state.motion.playing);
      try {
        // Playing means B follows the motion: switch to motion mode first if needed.
        if (playing && currentMode() !== 'motion') await setMode('motion');
        showMotion(await api('/api/motion', { playing }));
      } catch (err) { showError(err); }
    });
    tl.addEventListener('pointerdown', () => { scrubbing = true; });
    tl.addEventListener('pointerup', () => { scrubbing = false; });
    tl.addEventListener('change', () => { scrubbing = false; });
    tl.addEventListener('input', async () => {
      $('motion-time').textContent = `${Number(tl.value).toFixed(3)} / ${info.motion.seconds.toFixed(3)} s`;
      try {
        if (currentMode() !== 'motion' && info.modes.includes('motion')) await setMode('motion');
        await scrubPoster.send({ t: Number(tl.value) });
      } catch { /* shown by the poster */ }
    });
  }

  // Spheres.
  const show = $('show-spheres');
  const bodySel = $('sphere-body');
  const level = $('level');
  const anyMeshless = !info.bodies.a.has_mesh || !info.bodies.b.has_mesh;
  // Without meshes, the leaves are the picture: show them from the start.
  if (anyMeshless) {
    show.checked = true;
    bodySel.value = info.bodies.a.has_mesh ? 'b' : 'a';
  }
  const setLevelRange = () => {
    const levels = info.bodies[bodySel.value].levels;
    level.max = String(Math.max(0, levels - 1));
    level.value = String(Math.max(0, levels - 1)); // the leaves: the spheres that count
    $('level-value').textContent = level.value;
  };
  setLevelRange();
  show.addEventListener('change', updateSpheres);
  bodySel.addEventListener('change', () => { setLevelRange(); updateSpheres(); });
  level.addEventListener('input', () => { $('level-value').textContent = level.value; updateSpheres(); });
}

let scrubbing = false;
const scrubPoster = new LatestOnlyPoster('/api/motion', 16, (_body, answer) => showMotion(answer));

function showMotion(m) {
  $('play').textContent = m.playing ? 'pause' : 'play';
  $('play').classList.toggle('active', !!m.playing);
  if (!scrubbing) {
    $('timeline').value = String(m.t);
    $('motion-time').textContent = `${m.t.toFixed(3)} / ${m.seconds.toFixed(3)} s`;
  }
}

/** Shows or hides the inspected spheres, (re)loads them, and makes the meshes see-through
 *  while they are shown. */
async function updateSpheres() {
  const shown = $('show-spheres').checked;
  const body = $('sphere-body').value;
  const level = Number($('level').value);
  ist.spheres = { shown, body, level, count: inspectLayer.count, loading: shown };
  for (const name of ['a', 'b']) {
    const m = bodies[name].material;
    if (!m) continue;
    m.transparent = shown;
    m.opacity = shown ? 0.28 : 1;
    m.depthWrite = !shown;
    m.needsUpdate = true;
  }
  if (!shown) {
    inspectLayer.setVisible(false);
    for (const name of ['a', 'b']) standIn[name]?.setVisible(true);
    $('sphere-count').textContent = '—';
    return;
  }
  $('sphere-count').textContent = 'loading…';
  try {
    await inspectLayer.load(body, level);
  } catch (err) {
    showError(err);
    return;
  }
  // A later change may have come in while loading: only the latest one writes the panel.
  if ($('sphere-body').value !== body || Number($('level').value) !== level || !$('show-spheres').checked) return;
  inspectLayer.setVisible(true);
  // A stand-in showing the same spheres would only fight with them in the depth buffer.
  for (const name of ['a', 'b']) {
    standIn[name]?.setVisible(!(name === body && standIn[name].level === level));
  }
  $('sphere-count').textContent = `${inspectLayer.count.toLocaleString('en')} spheres (${body.toUpperCase()}, level ${level})`;
  ist.spheres = { shown, body, level, count: inspectLayer.count, loading: false };
}

// ---------------------------------------------------------------------------------------
// Contact map: both surfaces coloured per vertex by their signed gap to the other body
// ---------------------------------------------------------------------------------------
//
// The server's worker maps B's pose whenever it changes (the library's exact gaps, capped
// at 0.5 mm) and publishes one band index per vertex (/api/contact-map/bands: u32 seq,
// u32 Va, u32 Vb, u32 bands, 7×f64 B's pose of the map, then Va + Vb bytes, in the order
// of /api/mesh's vertices). While the mode is on the page asks for the map after the one it
// shows (`?after=seq`: the server answers when there is a newer one, so that a map reaches
// the meshes one request after it is made) and writes it into the meshes' `color`
// attributes through the palette of /api/info's legend (the colour scale of
// `ist occlusion-map`'s PLY files).

const BANDS_HEADER = 72;

const contactMap = {
  palette: null, // Uint8Array, 3 bytes (linear RGB) per band
  shownSeq: 0, // the map the meshes show
  polling: false, // the loop of ?after= requests runs
  teethSeq: 0, // the map the per-tooth list shows
  teethAt: -Infinity,
  teethFetching: false,
  asked: null, // { on, at }: what this page last asked for (the state may lag it)
};

/** The legend's sRGB colours as the linear RGB bytes vertex colours are read as. */
function paletteOf(legend) {
  const p = new Uint8Array(legend.length * 3);
  const c = new THREE.Color();
  legend.forEach((b, k) => {
    c.setRGB(b.rgb[0] / 255, b.rgb[1] / 255, b.rgb[2] / 255, THREE.SRGBColorSpace);
    p[3 * k] = Math.round(c.r * 255);
    p[3 * k + 1] = Math.round(c.g * 255);
    p[3 * k + 2] = Math.round(c.b * 255);
  });
  return p;
}

const rgbCss = (rgb) => `rgb(${rgb[0]}, ${rgb[1]}, ${rgb[2]})`;

function setupContactMap(info) {
  const cm = info.contact_map;
  ist.contactMap.available = !!(cm && cm.available);
  if (!ist.contactMap.available) return;
  contactMap.palette = paletteOf(cm.legend);
  $('contact-map-panel').hidden = false;
  const rows = cm.legend.map((b) => `<tr><td><span class="swatch" style="background:${rgbCss(b.rgb)}"></span></td><td>${b.name}</td></tr>`);
  $('cm-legend').innerHTML = rows.join('');
  $('cm-show').addEventListener('change', () => { showBodies($('cm-show').value); $('cm-show').blur(); });
  $('contact-map').addEventListener('change', async () => {
    const on = $('contact-map').checked;
    contactMap.asked = { on, at: performance.now() };
    showContactMapMode(on);
    try {
      await api('/api/contact-map', { on });
    } catch (err) {
      showError(err);
      contactMap.asked = null;
    }
  });
}

/** Whether the mode is on: what this page just asked for (for a second), else the state's. */
function contactMapOn(st) {
  const a = contactMap.asked;
  if (a && performance.now() - a.at < 1000) return a.on;
  return !!(st && st.on);
}

/** `both` bodies, or `a` / `b` alone: the surfaces that touch face each other, so that one
 *  is seen only with the other hidden. Alone, the camera turns to the body's side that faces
 *  the other (from a little in front: -y in the jaw data's frame, as in frameBodies), and
 *  the contact overlays (patches, arrows, closest points) are hidden. */
function showBodies(which) {
  $('cm-show').value = which;
  bodyA.visible = which !== 'b';
  bodyB.visible = which !== 'a';
  ist.contactMap.shown = which;
  if (which === 'both') return;
  hideContactOverlays();
  bodyB.updateMatrixWorld();
  const boxOf = (n) => (n === 'a' ? bodies.a.box.clone() : bodies.b.box.clone().applyMatrix4(bodyB.matrixWorld));
  const box = boxOf(which);
  const centre = box.getCenter(new THREE.Vector3());
  const toOther = boxOf(which === 'a' ? 'b' : 'a').getCenter(new THREE.Vector3()).sub(centre);
  if (toOther.lengthSq() < 1e-12) toOther.set(0, 0, which === 'a' ? -1 : 1);
  const dir = toOther.normalize().add(new THREE.Vector3(0, -0.35, 0)).normalize();
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  const fov = THREE.MathUtils.degToRad(camera.fov);
  const hfov = 2 * Math.atan(Math.tan(fov / 2) * freeWidth() / window.innerHeight);
  const dist = radius / Math.sin(Math.min(fov, hfov) / 2) * 1.05;
  camera.position.copy(centre).addScaledVector(dir, dist);
  camera.near = dist / 100;
  camera.far = dist * 100;
  camera.updateProjectionMatrix();
  orbit.target.copy(centre);
  orbit.update();
}

/** Switches the meshes between their plain colours and the vertex colours of the map. */
function showContactMapMode(on) {
  ist.contactMap.on = on;
  $('contact-map').checked = on;
  if ($('cm-overlay').hidden === on) {
    $('cm-overlay').hidden = !on;
    onResize(); // the legend takes the view's left edge
  }
  $('cm-show').disabled = !on;
  if (!on && ist.contactMap.shown !== 'both') showBodies('both');
  for (const name of ['a', 'b']) {
    const b = bodies[name];
    if (!b.mesh) continue;
    const geo = b.mesh.geometry;
    if (on && !geo.getAttribute('color')) {
      // Far (the last band) until the first map arrives.
      const n = geo.getAttribute('position').count;
      const col = new Uint8Array(n * 3);
      const p = contactMap.palette, far = p.length - 3;
      for (let i = 0; i < n; i++) { col[3 * i] = p[far]; col[3 * i + 1] = p[far + 1]; col[3 * i + 2] = p[far + 2]; }
      geo.setAttribute('color', new THREE.BufferAttribute(col, 3, true));
    }
    if (b.material.vertexColors !== on) {
      b.material.vertexColors = on;
      b.material.color.set(on ? 0xffffff : b.color);
      b.material.needsUpdate = true;
    }
  }
}

/** Writes one body's band indices into its mesh's colours; returns the count per band. */
function paintBands(name, bands) {
  const geo = bodies[name].mesh.geometry;
  const attr = geo.getAttribute('color');
  if (!attr || attr.count !== bands.length) {
    throw new Error(`contact map of ${name.toUpperCase()}: ${bands.length} vertices, its mesh has ${attr ? attr.count : '?'}`);
  }
  const col = attr.array, p = contactMap.palette;
  const last = p.length / 3 - 1;
  const counts = new Array(last + 1).fill(0);
  for (let i = 0; i < bands.length; i++) {
    const b = Math.min(bands[i], last);
    counts[b]++;
    const k = 3 * b, j = 3 * i;
    col[j] = p[k]; col[j + 1] = p[k + 1]; col[j + 2] = p[k + 2];
  }
  attr.needsUpdate = true;
  return counts;
}

/** Shows one answer of /api/contact-map/bands (unless the meshes show that map already). */
function showBands(buf) {
  const dv = new DataView(buf);
  const seq = dv.getUint32(0, true), na = dv.getUint32(4, true), nb = dv.getUint32(8, true);
  if (buf.byteLength !== BANDS_HEADER + na + nb) throw new Error('bad contact map data');
  if (seq === contactMap.shownSeq) return;
  const pose = [0, 1, 2, 3, 4, 5, 6].map((k) => dv.getFloat64(16 + 8 * k, true));
  const bands = new Uint8Array(buf, BANDS_HEADER);
  const t0 = performance.now();
  const counts = { a: paintBands('a', bands.subarray(0, na)), b: paintBands('b', bands.subarray(na)) };
  const paint_ms = performance.now() - t0;
  contactMap.shownSeq = seq;
  Object.assign(ist.contactMap, { shownSeq: seq, pose, counts, paint_ms, updates: ist.contactMap.updates + 1 });
}

const pause = (ms) => new Promise((r) => setTimeout(r, ms));

/** While the mode is on: ask for the map after the one shown, show it, ask again. */
async function pollBands() {
  if (contactMap.polling) return;
  contactMap.polling = true;
  try {
    while (ist.contactMap.on) {
      let buf = null;
      try {
        buf = await apiBinary(`/api/contact-map/bands?after=${contactMap.shownSeq}`);
        if (buf && ist.contactMap.on) showBands(buf);
      } catch (err) {
        showError(err);
        await pause(1000);
      }
      if (!buf) await pause(200); // no map yet
    }
  } finally {
    contactMap.polling = false;
  }
}

/** A gap for the per-tooth list: mm with 3 decimals, "> 0.5" beyond the colour scale (the
 *  server's gaps stop at the cap, just above its end). */
function gapText(g, cap, top) {
  if (g === null || g === undefined) return '—';
  return g >= cap ? `> ${top}` : g.toFixed(3);
}

function showTeeth(m) {
  const legend = ist.info.contact_map.legend;
  const top = legend[legend.length - 2].below; // the scale's end (0.5 mm)
  const table = (title, rows) => {
    if (!rows) return '';
    const body = rows.map((t) => {
      const sw = t.band === null ? '' : `<span class="swatch" style="background:${rgbCss(legend[t.band].rgb)}"></span> `;
      return `<tr><td>${t.tooth}</td><td>${sw}${gapText(t.min_gap, m.cap, top)}</td><td>${t.area_within_0_1.toFixed(1)}</td><td>${t.area_within_0_2.toFixed(1)}</td><td>${t.spots}</td></tr>`;
    });
    return `<h3>${title}</h3><table><tr><th>tooth</th><th>min gap</th><th>≤0.1 mm²</th><th>≤0.2 mm²</th><th>spots</th></tr>${body.join('')}</table>`;
  };
  $('cm-teeth').innerHTML = table('A (fixed)', m.teeth.a) + table('B (moved)', m.teeth.b);
  $('cm-teeth').hidden = false;
  ist.contactMap.teeth = { seq: m.seq, a: m.teeth.a, b: m.teeth.b };
}

async function fetchTeeth() {
  contactMap.teethFetching = true;
  contactMap.teethAt = performance.now();
  try {
    const m = await api('/api/contact-map');
    if (m.seq > 0 && ist.contactMap.on) { showTeeth(m); contactMap.teethSeq = m.seq; }
  } catch (err) {
    showError(err);
  } finally {
    contactMap.teethFetching = false;
  }
}

/** The state's `contact_map`: mode, status line, and a newer map to fetch. */
function syncContactMap(st) {
  if (!st || !ist.contactMap.available) return;
  const on = contactMapOn(st);
  if (on !== ist.contactMap.on && loaded) showContactMapMode(on);
  Object.assign(ist.contactMap, { status: st.status, seq: st.seq, rate_hz: st.rate_hz, compute_ms: st.compute_ms });
  const status = $('cm-status');
  if (!on) status.textContent = 'off';
  else if (st.status === 'failed') status.textContent = `failed: ${st.error}`;
  else if (st.status !== 'ready') status.textContent = 'preparing the meshes…';
  else status.textContent = `${num(st.rate_hz, 3)} maps/s, ${num(st.compute_ms, 3)} ms a map`;
  status.title = st.error || `gaps ${num(st.gaps_ms, 3)} ms; meshes prepared in ${num(st.prepare_s, 3)} s`;
  if (!on || !loaded) return;
  pollBands();
  if (st.seq === 0) return;
  // The per-tooth list: a few times a second at most (the server makes it on request).
  const teeth = ist.info.contact_map.teeth;
  if ((teeth.a || teeth.b) && st.seq !== contactMap.teethSeq && !contactMap.teethFetching
    && performance.now() - contactMap.teethAt > 300) fetchTeeth();
}

// ---------------------------------------------------------------------------------------
// Shift-drag: move B's target in the camera's view plane (no gizmo needed)
// ---------------------------------------------------------------------------------------

/** Pointer position in normalized device coordinates. */
function ndcOf(e) {
  const r = canvas.getBoundingClientRect();
  return new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
}

function setupShiftDrag() {
  const ray = new THREE.Raycaster();
  let drag = null; // { plane, startHit, startPos, pointerId }
  const hit = (e, plane) => {
    ray.setFromCamera(ndcOf(e), camera);
    return ray.ray.intersectPlane(plane, new THREE.Vector3());
  };
  // Capture phase on window: runs before OrbitControls' and the gizmo's listeners on the
  // canvas, so that a Shift-drag neither orbits the view nor grabs a gizmo handle.
  window.addEventListener('pointerdown', (e) => {
    if (!e.shiftKey || e.button !== 0 || e.target !== canvas) return;
    e.stopPropagation();
    e.preventDefault();
    const normal = camera.getWorldDirection(new THREE.Vector3());
    const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(normal, proxy.position);
    const startHit = hit(e, plane);
    if (!startHit) return;
    drag = { plane, startHit, startPos: proxy.position.clone(), pointerId: e.pointerId };
    dragging = true;
  }, true);
  window.addEventListener('pointermove', (e) => {
    if (!drag || e.pointerId !== drag.pointerId) return;
    e.stopPropagation();
    const h = hit(e, drag.plane);
    if (!h) return;
    proxy.position.copy(drag.startPos).add(h.sub(drag.startHit));
    proxy.updateMatrixWorld();
    updatePoseInput();
    sendPose(poseFromProxy()).catch(() => {});
  }, true);
  const end = (e) => {
    if (!drag || e.pointerId !== drag.pointerId) return;
    e.stopPropagation();
    drag = null;
    dragging = false;
  };
  window.addEventListener('pointerup', end, true);
  window.addEventListener('pointercancel', end, true);
}

// ---------------------------------------------------------------------------------------
// Render loop
// ---------------------------------------------------------------------------------------

let loaded = false; // meshes (or stand-in spheres) of both bodies are in the scene
let framed = false; // the camera has been framed on the bodies (needs B's first pose)

/** Widths the panel (right, P) and the contact map's legend (left, L, while shown) take
 *  from the view: 0 where the window is too narrow for leaving them free to help (the
 *  legend's where less than 600 px would be left). */
function sideWidths() {
  const W = window.innerWidth;
  const P = $('panel').getBoundingClientRect().width + 16;
  const o = $('cm-overlay');
  const L = o && !o.hidden ? o.getBoundingClientRect().width + 16 : 0;
  if (L > 0 && W - P - L >= 600) return { P, L };
  return W > 2.5 * P ? { P, L: 0 } : { P: 0, L: 0 };
}

/** Width of the window the panel (and the legend) leave free. */
function freeWidth() {
  const { P, L } = sideWidths();
  return window.innerWidth - P - L;
}

/** Sizes the canvas to the window and centres the view on the part the panel (and the
 *  legend) leave free: the projection is that of a window wider by the difference of their
 *  widths, of which the canvas shows the part that puts its centre in the middle of the
 *  free part (PerspectiveCamera.setViewOffset). */
function onResize() {
  const W = window.innerWidth, H = window.innerHeight;
  const { P, L } = sideWidths();
  const d = P - L;
  renderer.setSize(W, H);
  if (d !== 0) camera.setViewOffset(W + Math.abs(d), H, Math.max(d, 0), 0, W, H); // also sets the aspect
  else { camera.clearViewOffset(); camera.aspect = W / H; }
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', onResize);

function frame() {
  requestAnimationFrame(frame);
  if (loaded && ist.state && !framed) { frameBodies(); framed = true; }
  orbit.update();
  renderer.render(scene, camera);
  ist.frames++;
  if (!ist.ready && loaded && framed) ist.ready = true; // this frame showed the bodies
}

// ---------------------------------------------------------------------------------------
// Start
// ---------------------------------------------------------------------------------------

async function main() {
  onResize();
  requestAnimationFrame(frame);
  try {
    ist.info = await api('/api/info');
  } catch (err) {
    showError(err);
    $('conn').textContent = 'no server';
    return;
  }
  setupPanel(ist.info);
  setupContactMap(ist.info);
  setupShiftDrag();
  connect();
  try {
    await Promise.all([loadBody('a'), loadBody('b'), loadSplint(ist.info)]);
  } catch (err) {
    showError(err);
  }
  // B's pivot is known now: put the proxy where the latest state says.
  if (ist.state) setProxyFromPose(ist.state.target_b);
  loaded = true;
  if ($('show-spheres').checked) updateSpheres();
  // The meshes are there now: the contact map's colours (the mode may have been turned on,
  // here or by --contact-map, while they loaded).
  if (ist.contactMap.available) {
    showContactMapMode(contactMapOn(ist.state && ist.state.contact_map));
    if (ist.state) syncContactMap(ist.state.contact_map);
  }
}

main();
