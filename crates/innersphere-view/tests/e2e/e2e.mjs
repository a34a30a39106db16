// End-to-end test of the `ist view` page: a headless Chromium (software WebGL) drives the
// page served by `ist view --demo` and checks what a user would see and do.
//
//   node e2e.mjs URL OUTDIR        (run.sh starts the server and calls this)
//
// Checks, in order (any failure → exit 1, after the rest has been tried where it can):
//   1. the page loads without script errors and reports ready (window.__ist.ready) in 60 s;
//   2. the WebGL canvas #view is not blank (a screenshot with more than one colour);
//      screenshot start.png;
//   3. the API answers: GET /api/info, GET /api/state (fields of the contract), a bad
//      POST /api/pose gets 400 with {"error"}, /api/spheres at level 0 is one sphere;
//   4. the contact indicator at the start is recorded (not assumed);
//   5. a Shift-drag on the canvas from B's centre towards A moves B's target on the server,
//      and so does a plain drag of the gizmo's centre handle; keys r / t switch its mode;
//      then B is put clearly apart (#contact off, distance > 0, the closest-point line);
//      screenshot apart.png;
//   6. a pose typed in #pose-input (the identity, where the demo pair interlocks; then B
//      pushed further into A if needed) gives #contact.on, a #volume > 0 that differs from
//      before, and overlays; screenshot contact.png;
//   7. spheres: #show-spheres on, #level moved (level 0 = 1 sphere; deeper = more);
//      screenshot spheres.png;
//   8. motion (if the demo has one): #play advances the motion time, #timeline scrubs;
//   9. haptic mode (if offered): the tool stops short of the device pose, a device force,
//      the ghost and the device-force arrow drawn, the collision thread's rate shown;
//      screenshot haptic.png;
//  10. contact map (if offered): the panel's checkbox turns it on: vertex colours on both
//      meshes, the legend (7 bands); apart every vertex is far (grey); in contact the
//      contact bands appear on both and the colours change again when B moves deeper; the
//      per-tooth list (run.sh's demo teeth); the binary API's size; B alone shows its
//      surface in the contact colours (screenshot contact-map.png); while B is dragged
//      (poses at 60 Hz) maps come at ≥ 10 Hz and the page's colours follow to the last
//      pose; off again: the plain colours.

import { chromium } from 'playwright-core';
import fs from 'node:fs';
import path from 'node:path';

const [url, outDir] = process.argv.slice(2);
if (!url || !outDir) {
  console.error('usage: node e2e.mjs URL OUTDIR');
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const base = url.replace(/\/+$/, '');

const results = []; // { name, ok, detail }
function check(name, ok, detail = '') {
  results.push({ name, ok: !!ok, detail });
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${name}${detail ? ` — ${detail}` : ''}`);
  return !!ok;
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const num3 = (x) => (typeof x === 'number' ? x.toPrecision(3) : String(x));

/** Polls `fn` (async, returns truthy when done) until it is truthy or `ms` pass. */
async function until(fn, ms, every = 100) {
  const end = Date.now() + ms;
  let last;
  while (Date.now() < end) {
    last = await fn();
    if (last) return last;
    await sleep(every);
  }
  return last;
}

async function getJson(p) {
  const r = await fetch(base + p);
  return { status: r.status, body: await r.json().catch(() => null) };
}
async function postJson(p, body) {
  const r = await fetch(base + p, {
    method: 'POST',
    headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify(body),
  });
  return { status: r.status, body: await r.json().catch(() => null) };
}

const t0 = Date.now();
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--use-gl=swiftshader', '--enable-unsafe-swiftshader'],
});
let exitCode = 0;
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  const pageErrors = [];
  const consoleErrors = [];
  page.on('pageerror', (e) => pageErrors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });

  // 1. Load and ready.
  await page.goto(base + '/', { waitUntil: 'load' });
  let ready = true;
  try {
    await page.waitForFunction(() => window.__ist && window.__ist.ready, null, { timeout: 60000 });
  } catch {
    ready = false;
  }
  check('page ready (window.__ist.ready)', ready, `${((Date.now() - t0) / 1000).toFixed(1)} s after launch`);
  if (!ready) {
    // Say why: the page's errors, what the hooks hold, and what it looked like.
    const hooks = await page.evaluate(() => window.__ist
      ? { ready: window.__ist.ready, frames: window.__ist.frames, hasInfo: !!window.__ist.info, hasState: !!window.__ist.state }
      : null).catch((e) => String(e));
    await page.screenshot({ path: path.join(outDir, 'not-ready.png') }).catch(() => {});
    throw new Error(`page never became ready: __ist ${JSON.stringify(hooks)}; page errors: ${pageErrors.join(' | ') || 'none'}; console errors: ${consoleErrors.join(' | ') || 'none'}`);
  }
  // A few more frames: the state stream has filled the panel.
  await page.waitForFunction(() => window.__ist.frames > 5 && window.__ist.state, null, { timeout: 20000 });

  // 2. Not blank: count the colours of a screenshot of the canvas (decoded by the browser).
  const shot = await page.locator('#view').screenshot();
  const colours = await page.evaluate(async (b64) => {
    const img = new Image();
    img.src = `data:image/png;base64,${b64}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width; c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    const seen = new Set();
    for (let i = 0; i < d.length; i += 4 * 7) seen.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
    return seen.size;
  }, shot.toString('base64'));
  check('canvas #view is not blank', colours > 1, `${colours} distinct colours sampled`);
  fs.writeFileSync(path.join(outDir, 'start.png'), shot);

  // 3. The API directly.
  const info = await getJson('/api/info');
  check('GET /api/info', info.status === 200 && info.body && info.body.bodies && info.body.bodies.a && info.body.bodies.b,
    info.body ? `a: ${info.body.bodies?.a?.leaves} leaves, ${info.body.bodies?.a?.levels} levels; b: ${info.body.bodies?.b?.leaves} leaves; modes ${JSON.stringify(info.body.modes)}; motion ${JSON.stringify(info.body.motion)}` : `status ${info.status}`);
  const st = await getJson('/api/state');
  const stOk = st.status === 200 && st.body
    && Array.isArray(st.body.pose_b) && st.body.pose_b.length === 7
    && Array.isArray(st.body.target_b) && st.body.target_b.length === 7
    && typeof st.body.contact === 'boolean' && typeof st.body.volume === 'number'
    && Array.isArray(st.body.patches) && st.body.loop && Array.isArray(st.body.loop.history_us);
  check('GET /api/state has the contract fields', stOk,
    st.body ? `mode ${st.body.mode}, loop ${st.body.loop?.rate_hz?.toFixed?.(0)} Hz, tick ${st.body.loop?.tick_us?.toFixed?.(2)} µs` : `status ${st.status}`);
  const bad = await postJson('/api/pose', { pose_b: [1, 2] });
  check('POST /api/pose {"pose_b":[1,2]} → 400 {"error"}', bad.status === 400 && bad.body && typeof bad.body.error === 'string',
    `${bad.status} ${JSON.stringify(bad.body)}`);
  const root = await fetch(`${base}/api/spheres?body=a&level=0`);
  const rootBytes = root.ok ? (await root.arrayBuffer()).byteLength : -1;
  check('GET /api/spheres?body=a&level=0 → one sphere (16 bytes)', rootBytes === 16, `${root.status}, ${rootBytes} bytes`);

  // 4. The contact indicator at the start (recorded, not assumed).
  const readPanel = () => page.evaluate(() => ({
    contact: document.getElementById('contact').classList.contains('on'),
    contactText: document.getElementById('contact').textContent,
    volume: parseFloat(document.getElementById('volume').textContent),
    volumeText: document.getElementById('volume').textContent,
    distance: document.getElementById('distance').textContent,
    force: document.getElementById('force').textContent,
    rate: document.getElementById('rate').textContent,
    tick: document.getElementById('tick').textContent,
  }));
  const modeBefore = await page.evaluate(() => window.__ist.state.mode);
  const start = await readPanel();
  check('contact indicator readable at the start', start.contactText === 'contact' || start.contactText === 'apart',
    `${start.contactText} (class on: ${start.contact}), distance ${start.distance}, volume ${start.volumeText}, in ${modeBefore} mode`);
  check('loop numbers shown', /\d/.test(start.rate) && /\d/.test(start.tick), `rate ${start.rate}, tick ${start.tick}`);

  // Drive B by hand. From motion mode the first hand move switches to free mode (checked
  // below); from haptic mode, choose free mode in #mode.
  if (modeBefore === 'haptic') {
    await page.selectOption('#mode', 'free');
    await until(() => page.evaluate(() => window.__ist.state.mode === 'free'), 5000);
  }

  // 5. Shift-drag on the canvas from B's centre towards A's.
  const targetBefore = (await getJson('/api/state')).body.target_b;
  const [bx, by] = await page.evaluate(() => window.__ist.screenOfB());
  const [ax, ay] = await page.evaluate(() => window.__ist.screenOfA());
  const dx = (ax - bx) * 0.5, dy = (ay - by) * 0.5 || 40; // half way (at least 40 px)
  await page.keyboard.down('Shift');
  await page.mouse.move(bx, by);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) { await page.mouse.move(bx + (dx * i) / 10, by + (dy * i) / 10); await sleep(20); }
  await page.mouse.up();
  await page.keyboard.up('Shift');
  const moved = await until(async () => {
    const t = (await getJson('/api/state')).body.target_b;
    const d = Math.hypot(t[0] - targetBefore[0], t[1] - targetBefore[1], t[2] - targetBefore[2]);
    return d > 1e-3 ? d : 0;
  }, 3000);
  if (modeBefore === 'motion') {
    const m = await until(async () => ((await getJson('/api/state')).body.mode === 'free' ? 'free' : null), 3000);
    check('a hand move leaves motion mode (→ free)', m === 'free', `mode ${m || (await getJson('/api/state')).body.mode}`);
  }
  check('Shift-drag moves B\'s target on the server', moved > 0, `moved ${Number(moved || 0).toFixed(3)} mm (from screen ${bx.toFixed(0)},${by.toFixed(0)} by ${dx.toFixed(0)},${dy.toFixed(0)} px)`);

  // 5a. The gizmo: a plain drag (no Shift) from its centre handle (at B's centre: it moves
  // in the view plane) moves B's target too; the keys r / t switch rotate / translate.
  await sleep(300); // the proxy has caught up with the server's target
  const targetMid = (await getJson('/api/state')).body.target_b;
  const [gx, gy] = await page.evaluate(() => window.__ist.screenOfB());
  await page.mouse.move(gx, gy);
  await sleep(100); // hover: the gizmo picks its handle
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) { await page.mouse.move(gx + 6 * i, gy + 3 * i); await sleep(20); }
  await page.mouse.up();
  const gmoved = await until(async () => {
    const t = (await getJson('/api/state')).body.target_b;
    const d = Math.hypot(t[0] - targetMid[0], t[1] - targetMid[1], t[2] - targetMid[2]);
    return d > 1e-3 ? d : 0;
  }, 3000);
  check('gizmo drag (centre handle) moves B\'s target', gmoved > 0, `moved ${Number(gmoved || 0).toFixed(3)} mm`);
  await page.mouse.move(5, 5);
  await page.keyboard.press('r');
  const rot = await page.evaluate(() => document.getElementById('gizmo-rotate').classList.contains('active'));
  await page.keyboard.press('t');
  const tra = await page.evaluate(() => document.getElementById('gizmo-translate').classList.contains('active'));
  check('keys r / t switch the gizmo to rotate / translate', rot && tra);

  // 5b. Clearly apart (B's bounding sphere off A's, away from A), whatever the start was:
  // the "before" of the contact check, and a check of the apart display.
  const ib = info.body.bodies;
  const centre = (b) => b.bbox_min.map((x, k) => (x + b.bbox_max[k]) / 2);
  const radius = (b) => Math.hypot(...b.bbox_max.map((x, k) => x - b.bbox_min[k])) / 2;
  const cA = centre(ib.a), cB = centre(ib.b);
  let u = cB.map((x, k) => x - cA[k]);
  const un = Math.hypot(...u);
  u = un > 1e-9 ? u.map((x) => x / un) : [0, 0, -1];
  const far = (radius(ib.a) + radius(ib.b)) * 1.2;
  const apartPose = [0, 1, 2].map((k) => cA[k] + u[k] * far - cB[k]).concat([1, 0, 0, 0]);
  await page.evaluate((p) => window.__ist.setPose(p), apartPose);
  await until(() => page.evaluate(() => !document.getElementById('contact').classList.contains('on')
    && parseFloat(document.getElementById('distance').textContent) > 0), 3000);
  await sleep(200);
  const before = await readPanel();
  const apartOverlays = await page.evaluate(() => window.__ist.overlays());
  check('B moved away: apart, distance > 0, closest-point line', !before.contact && before.contactText === 'apart'
    && parseFloat(before.distance) > 0 && apartOverlays.line && apartOverlays.discs === 0,
  `pose [${apartPose.map((x) => x.toFixed(2)).join(' ')}] → ${before.contactText}, distance ${before.distance}, volume ${before.volumeText}`);
  await page.screenshot({ path: path.join(outDir, 'apart.png') });

  // 6. Type a pose where the pair overlaps: the identity (the demo's interlocking pose),
  // then B lifted into A step by step if the identity only touches.
  let contactPose = null;
  for (const tz of [0, 0.3, 0.6, 1.0, 1.5, 2.0, 3.0]) {
    const pose = `0 0 ${tz} 1 0 0 0`;
    await page.fill('#pose-input', pose);
    await page.click('#pose-apply');
    const got = await until(() => page.evaluate(() => {
      const c = document.getElementById('contact');
      const v = parseFloat(document.getElementById('volume').textContent);
      return c.classList.contains('on') && v > 0;
    }), 2000);
    if (got) { contactPose = pose; break; }
  }
  await sleep(300); // a few states: numbers settle, overlays drawn
  const after = await readPanel();
  check('typed pose gives contact (#contact.on)', contactPose && after.contact && after.contactText === 'contact',
    `pose "${contactPose}" → ${after.contactText}`);
  check('#volume > 0 and changed', after.volume > 0 && after.volumeText !== before.volumeText,
    `${before.volumeText} → ${after.volumeText}, force ${after.force}, distance ${after.distance}`);
  const serverState = (await getJson('/api/state')).body;
  check('server agrees: state.contact and volume > 0', serverState.contact === true && serverState.volume > 0,
    `volume ${serverState.volume}, ${serverState.patches.length} patches, |F| ${Math.hypot(...serverState.force).toPrecision(3)}`);
  const overlays = await page.evaluate(() => window.__ist.overlays && window.__ist.overlays());
  if (overlays) check('contact overlays drawn (patches, force arrow)', overlays.discs > 0 && overlays.force, JSON.stringify(overlays));
  // setPose (the test hook) resolves with the server's answer for that pose. Push B a
  // little further into A: the volume must grow (and the picture shows more contact).
  const hook = contactPose && await page.evaluate((p) => window.__ist.setPose(p), contactPose.split(' ').map(Number));
  check('__ist.setPose answers', hook && hook.contact === true && hook.volume > 0, `volume ${hook && hook.volume}`);
  if (hook) {
    const deeper = contactPose.split(' ').map(Number);
    deeper[2] += 0.25;
    const d = await page.evaluate((p) => window.__ist.setPose(p), deeper);
    check('B 0.25 mm further into A: larger volume', d && d.volume > hook.volume,
      `${hook.volume} → ${d && d.volume} mm³, ${d && d.patches.length} patches`);
    await until(() => page.evaluate((v) => Math.abs(window.__ist.state.volume - v) <= 1e-9 * Math.max(1, v), d.volume), 2000);
    await sleep(300);
    const ov = await page.evaluate(() => window.__ist.overlays());
    check('overlays at the deeper pose (patch discs, force arrow)', ov.discs > 0 && ov.force, JSON.stringify(ov));
  }
  await page.mouse.move(5, 5); // off the gizmo: no hover highlight in the pictures
  await sleep(100);
  await page.screenshot({ path: path.join(outDir, 'contact.png') });

  // 7. Spheres: show them, move the level slider.
  const setLevel = (v) => page.$eval('#level', (el, v) => {
    el.value = String(v);
    el.dispatchEvent(new Event('input', { bubbles: true }));
    el.dispatchEvent(new Event('change', { bubbles: true }));
  }, v);
  const spheresAt = () => until(() => page.evaluate(() => {
    const s = window.__ist.spheres;
    return s.shown && !s.loading && s.count > 0 ? s : null;
  }), 30000);
  await page.check('#show-spheres');
  const first = await spheresAt();
  check('#show-spheres shows spheres', first && first.count > 0, first ? `${first.count} spheres of ${first.body} at level ${first.level}` : 'none');
  await setLevel(0);
  const lvl0 = await until(() => page.evaluate(() => { const s = window.__ist.spheres; return s.level === 0 && !s.loading ? s : null; }), 10000);
  check('#level 0 → the root sphere', lvl0 && lvl0.count === 1, lvl0 ? `${lvl0.count} sphere(s)` : 'no answer');
  const maxLevel = await page.$eval('#level', (el) => Number(el.max));
  const mid = Math.max(1, Math.min(maxLevel, Math.round(maxLevel * 0.6)));
  await setLevel(mid);
  const lvlMid = await until(() => page.evaluate((m) => { const s = window.__ist.spheres; return s.level === m && !s.loading ? s : null; }, mid), 30000);
  check(`#level ${mid} → more spheres`, lvlMid && lvlMid.count > 1, lvlMid ? `${lvlMid.count} spheres; panel "${await page.textContent('#sphere-count')}"` : 'no answer');
  await sleep(300);
  await page.screenshot({ path: path.join(outDir, 'spheres.png') });
  // B's spheres too (they follow B's pose).
  await page.selectOption('#sphere-body', 'b');
  const bSpheres = await until(() => page.evaluate(() => { const s = window.__ist.spheres; return s.body === 'b' && !s.loading && s.count > 0 ? s : null; }), 30000);
  check('B\'s spheres load', bSpheres && bSpheres.count > 0, bSpheres ? `${bSpheres.count} spheres at level ${bSpheres.level}` : 'none');
  await page.uncheck('#show-spheres');

  // 8. Motion: play, see the time advance, pause, scrub.
  if (info.body && info.body.motion) {
    await page.click('#play');
    const t1 = await until(async () => {
      const s = (await getJson('/api/state')).body;
      return s.motion && s.motion.playing && s.mode === 'motion' ? s.motion.t : null;
    }, 5000);
    // The time moves on (it may wrap at the end of the motion: any change will do).
    const t2 = await until(async () => {
      const t = (await getJson('/api/state')).body.motion?.t;
      return t !== undefined && Math.abs(t - t1) > 1e-3 ? t : null;
    }, 3000);
    check('#play plays the motion', t1 !== null && t1 !== undefined && t2 !== null && t2 !== undefined, `t ${t1} → ${t2}`);
    await page.click('#play');
    const paused = await until(async () => (await getJson('/api/state')).body.motion?.playing === false, 3000);
    check('#play again pauses', paused);
    const seconds = info.body.motion.seconds;
    await page.$eval('#timeline', (el, v) => {
      el.value = String(v);
      el.dispatchEvent(new Event('input', { bubbles: true }));
      el.dispatchEvent(new Event('change', { bubbles: true }));
    }, seconds / 2);
    const scrubbed = await until(async () => {
      const m = (await getJson('/api/state')).body.motion;
      return m && Math.abs(m.t - seconds / 2) < 0.01 ? m.t : null;
    }, 3000);
    check('#timeline scrubs the motion', scrubbed !== null && scrubbed !== undefined, `asked ${seconds / 2}, state t ${scrubbed}`);
    // The panel shows the time (the server may round it to its frame).
    const near = (t) => Math.abs(parseFloat(t) - seconds / 2) < 0.01;
    const shownTime = await until(async () => {
      const t = await page.textContent('#motion-time');
      return near(t) ? t : null;
    }, 3000) || await page.textContent('#motion-time');
    check('motion time shown (#motion-time)', near(shownTime), `"${shownTime}"`);
  } else {
    console.log('     (no motion in /api/info: motion checks skipped)');
  }

  // 9. Haptic mode (when offered): the gizmo is the device; push it into A: the drawn tool
  // stops short of it (pose_b ≠ target_b), the device renders a force, the page shows the
  // ghost of the device pose and the device-force arrow. Screenshot haptic.png.
  if (info.body && info.body.modes.includes('haptic') && contactPose) {
    await page.selectOption('#mode', 'haptic');
    await until(async () => (await getJson('/api/state')).body.mode === 'haptic', 3000);
    const deep = contactPose.split(' ').map(Number);
    deep[2] += 1.0;
    await page.evaluate((p) => window.__ist.setPose(p), deep);
    const hs = await until(async () => {
      const s = (await getJson('/api/state')).body;
      const gap = Math.hypot(s.pose_b[0] - s.target_b[0], s.pose_b[1] - s.target_b[1], s.pose_b[2] - s.target_b[2]);
      return s.mode === 'haptic' && gap > 1e-3 && Math.hypot(...s.device_force) > 0 ? { gap, f: Math.hypot(...s.device_force) } : null;
    }, 5000);
    check('haptic: the tool stops short of the device pose, a device force', hs,
      hs ? `tool ${hs.gap.toFixed(3)} mm from the device pose, |device force| ${hs.f.toPrecision(3)}` : 'no');
    await sleep(300);
    const ov = await page.evaluate(() => window.__ist.overlays());
    check('haptic: ghost of the device pose and device-force arrow drawn', ov.ghost && ov.device, JSON.stringify(ov));
    // The servo and the collision thread each at its own rate, both on the page.
    const rates = await until(async () => {
      const l = (await getJson('/api/state')).body.loop;
      const shown = await page.evaluate(() => !document.getElementById('collision-row').hidden
        && document.getElementById('collision').textContent);
      return l.collision_rate_hz > 100 && shown ? { servo: l.rate_hz, collision: l.collision_rate_hz, shown } : null;
    }, 3000);
    check('haptic: the collision thread\'s rate shown beside the loop\'s', rates,
      rates ? `servo ${rates.servo.toFixed(0)} Hz, collision ${rates.collision.toFixed(0)} Hz, page "${rates.shown}"` : 'no');
    await page.screenshot({ path: path.join(outDir, 'haptic.png') });
    await page.selectOption('#mode', 'free');
  }

  // 10. Contact map.
  const cmInfo = info.body && info.body.contact_map;
  if (cmInfo && cmInfo.available && contactPose) {
    const cm = () => page.evaluate(() => {
      const c = window.__ist.contactMap;
      return { ...c, vertexColors: c.vertexColors(), legendRows: c.legendRows(), overlayShown: c.overlayShown() };
    });
    const close7 = (p, q) => p && q && p.every((x, k) => Math.abs(x - q[k]) < 1e-9);
    /** The page's map once it shows B at `pose` (and a newer map than `after`). */
    const shownAt = (pose, after = 0) => until(async () => {
      const c = await cm();
      return c.shownSeq > after && close7(c.pose, pose) ? c : null;
    }, 20000);
    const sum = (a) => a.reduce((x, y) => x + y, 0);
    const panel = await page.evaluate(() => ({
      hidden: document.getElementById('contact-map-panel').hidden,
      checked: document.getElementById('contact-map').checked,
    }));
    const st0 = (await getJson('/api/state')).body.contact_map;
    check('contact map offered: panel shown, off at the start', !panel.hidden && !panel.checked && st0 && st0.on === false,
      `panel ${JSON.stringify(panel)}, state ${JSON.stringify(st0)}`);
    await page.evaluate((p) => window.__ist.setPose(p), apartPose);
    await page.check('#contact-map');
    const far = cmInfo.legend.length - 1;
    const apart = await shownAt(apartPose);
    check('contact map on: a map arrives, both meshes in vertex colours, legend shown',
      apart && apart.vertexColors.every(Boolean) && apart.legendRows === cmInfo.legend.length && apart.overlayShown,
      apart ? `map ${apart.shownSeq} (${apart.status}, ${num3(apart.compute_ms)} ms), ${apart.legendRows} legend rows, vertex colours ${apart.vertexColors}` : JSON.stringify(await cm()));
    check('apart: every vertex far (light grey)', apart && apart.counts.a[far] === sum(apart.counts.a) && apart.counts.b[far] === sum(apart.counts.b),
      apart ? `A ${JSON.stringify(apart.counts.a)}, B ${JSON.stringify(apart.counts.b)}` : 'no map');
    const cp = contactPose.split(' ').map(Number);
    await page.evaluate((p) => window.__ist.setPose(p), cp);
    const touch = await shownAt(cp, apart ? apart.shownSeq : 0);
    const inContact = (c) => c[0] + c[1] + c[2];
    check('B in contact: the colours change, contact bands (< 0.1 mm) on both',
      touch && inContact(touch.counts.a) > 0 && inContact(touch.counts.b) > 0,
      touch ? `map ${touch.shownSeq}: A ${JSON.stringify(touch.counts.a)}, B ${JSON.stringify(touch.counts.b)}` : JSON.stringify(await cm()));
    const deeper = cp.slice();
    deeper[2] += 0.25;
    await page.evaluate((p) => window.__ist.setPose(p), deeper);
    const deep = await shownAt(deeper, touch ? touch.shownSeq : 0);
    check('B deeper: newer map, more of both inside the other (purple)',
      touch && deep && deep.counts.a[0] > touch.counts.a[0] && deep.counts.b[0] > touch.counts.b[0],
      deep ? `map ${deep.shownSeq}: inside A ${touch && touch.counts.a[0]} → ${deep.counts.a[0]}, B ${touch && touch.counts.b[0]} → ${deep.counts.b[0]}` : 'no map');
    // The per-tooth list (run.sh gives the demo one molar per body).
    if (cmInfo.teeth.a && cmInfo.teeth.b) {
      const teeth = await until(async () => {
        const c = await cm();
        return c.teeth && deep && c.teeth.seq >= deep.shownSeq ? c.teeth : null;
      }, 5000);
      const rows = await page.evaluate(() => document.querySelectorAll('#cm-teeth td').length);
      check('per-tooth list: tooth 3 of A and 30 of B in contact, shown',
        teeth && teeth.a[0].tooth === 3 && teeth.b[0].tooth === 30 && teeth.a[0].min_gap < 0 && teeth.b[0].min_gap < 0
        && teeth.a[0].area_within_0_1 > 0 && rows === 10,
        teeth ? `A ${JSON.stringify(teeth.a[0])}; B ${JSON.stringify(teeth.b[0])}; ${rows} cells` : 'no list');
    }
    const meshA = new DataView(await (await fetch(`${base}/api/mesh?body=a`)).arrayBuffer());
    const meshB = new DataView(await (await fetch(`${base}/api/mesh?body=b`)).arrayBuffer());
    const bands = await (await fetch(`${base}/api/contact-map/bands`)).arrayBuffer();
    const bv = new DataView(bands);
    check('GET /api/contact-map/bands: one byte per vertex of each mesh', bands.byteLength === 72 + meshA.getUint32(0, true) + meshB.getUint32(0, true)
      && bv.getUint32(4, true) === meshA.getUint32(0, true) && bv.getUint32(8, true) === meshB.getUint32(0, true),
    `${bands.byteLength} bytes for ${meshA.getUint32(0, true)} + ${meshB.getUint32(0, true)} vertices`);
    // B alone: the camera turns to its surface that faces A, drawn in the map's colours
    // (pixels of the contact bands' red and purple hues in the picture).
    await page.mouse.move(5, 5);
    await page.selectOption('#cm-show', 'b');
    await sleep(500);
    const pic = await page.locator('#view').screenshot();
    fs.writeFileSync(path.join(outDir, 'contact-map.png'), pic);
    const hot = await page.evaluate(async (b64) => {
      const img = new Image();
      img.src = `data:image/png;base64,${b64}`;
      await img.decode();
      const c = document.createElement('canvas');
      c.width = img.width; c.height = img.height;
      const g = c.getContext('2d');
      g.drawImage(img, 0, 0);
      const d = g.getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i] > 90 && d[i] > 2 * d[i + 1] + 20) n++;
      return n;
    }, pic.toString('base64'));
    const alone = await page.evaluate(() => window.__ist.contactMap.shown);
    check('B alone: its surface facing A shows the contact colours (red/purple pixels)', alone === 'b' && hot > 200,
      `${hot} red or purple pixels`);
    await page.selectOption('#cm-show', 'both');
    // Dragging: B's pose changes at 60 Hz for 2 s, posted as a page posts a gizmo drag
    // (from here: this headless page, drawing in software, runs its tasks only between
    // frames of ~45 ms and would post and fetch at a few hertz).
    const u0 = (await cm()).updates;
    const s0 = (await getJson('/api/state')).body.contact_map.seq;
    const tDrag = Date.now();
    let rate = 0;
    let last = null;
    for (let i = 0; Date.now() - tDrag < 2000; i++) {
      last = cp.slice();
      last[0] = 0.4 * Math.sin(i / 10);
      last[2] += 0.1 * Math.cos(i / 7);
      await postJson('/api/pose', { pose_b: last });
      await sleep(16);
      if (i % 20 === 19) rate = Math.max(rate, (await getJson('/api/state')).body.contact_map.rate_hz);
    }
    const secs = (Date.now() - tDrag) / 1000;
    const maps = (await getJson('/api/state')).body.contact_map.seq - s0;
    const updates = (await cm()).updates - u0;
    const caught = await shownAt(last);
    check('dragging B (poses at 60 Hz): ≥ 10 maps/s; the page\'s colours follow, to the last pose',
      maps / secs >= 10 && updates > 0 && caught,
      `${(maps / secs).toFixed(1)} maps/s (state rate ${rate} Hz), ${(updates / secs).toFixed(1)} colour updates/s on the page, `
      + `last map ${caught ? caught.shownSeq : 'not'} shown (${caught ? num3(caught.paint_ms) : '?'} ms to paint)`);
    await page.uncheck('#contact-map');
    const off = await until(async () => {
      const c = await cm();
      const s = (await getJson('/api/state')).body.contact_map;
      return !c.on && !c.overlayShown && c.vertexColors.every((v) => !v) && s.on === false ? c : null;
    }, 3000);
    check('contact map off: the plain colours back, legend hidden, server off', off, off ? `vertex colours ${off.vertexColors}` : JSON.stringify(await cm()));
  } else {
    console.log('     (no contact map in /api/info: contact-map checks skipped)');
  }

  check('no script errors on the page', pageErrors.length === 0, pageErrors.join(' | '));
  if (consoleErrors.length) console.log(`     console errors: ${consoleErrors.join(' | ')}`);
} catch (err) {
  check('test ran to the end', false, String(err && err.stack ? err.stack : err));
} finally {
  await browser.close();
}

const failed = results.filter((r) => !r.ok);
console.log(`\n${results.length - failed.length}/${results.length} checks passed in ${((Date.now() - t0) / 1000).toFixed(1)} s; screenshots in ${outDir}`);
if (failed.length) {
  console.log(`failed: ${failed.map((r) => r.name).join('; ')}`);
  exitCode = 1;
}
process.exit(exitCode);
