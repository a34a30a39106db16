// The contact map's rate and latency while B is dragged, measured against a running
// `ist view` (no browser): poses posted at 60 Hz for SECONDS (what the page sends while the
// gizmo is dragged), closing from 1 mm apart into the bite at Z mm, then sliding ±0.4 mm
// sideways and turning by up to 1°; the maps fetched as the page fetches them
// (`/api/contact-map/bands?after=SEQ`). Run once with the mode off and once on, so that
// the 1 kHz loop's numbers can be compared.
//   node contact_map_rate.mjs URL [SECONDS=6] [Z=-0.25]
// Prints: maps per second, each map's latency (from the post of its pose to its arrival
// here), the server's time per map, and the loop's ticks over 1 ms and tick p99, mode off
// and on.

const [url, secondsArg, zArg] = process.argv.slice(2);
if (!url) { console.error('usage: node contact_map_rate.mjs URL [SECONDS] [Z]'); process.exit(2); }
const base = url.replace(/\/+$/, '');
const seconds = Number(secondsArg || 6);
const zBite = Number(zArg || -0.25);
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const get = async (p) => (await fetch(base + p)).json();
const post = async (p, body) => (await fetch(base + p, { method: 'POST', body: JSON.stringify(body) })).json();
const q = (xs, f) => { const s = [...xs].sort((a, b) => a - b); return s.length ? s[Math.min(s.length - 1, Math.floor(f * s.length))] : NaN; };

/** B's pose at time t of the drag: closing in the first third, then sliding and turning. */
function poseAt(t, T) {
  const close = Math.min(t / (T / 3), 1);
  const slide = Math.max(0, t - T / 3);
  const z = zBite + (1 - close) * 1.0 + 0.05 * Math.sin(slide * 5);
  const x = 0.4 * Math.sin(slide * 2.1);
  const y = 0.2 * Math.sin(slide * 1.3);
  const half = (Math.PI / 180) * 1.0 * Math.sin(slide * 1.7) / 2; // up to 1° about z
  return [x, y, z, Math.cos(half), 0, 0, Math.sin(half)];
}

async function drag(mapOn) {
  await post('/api/mode', { mode: 'free' });
  await post('/api/contact-map', { on: mapOn });
  await post('/api/pose', { pose_b: poseAt(0, seconds) });
  if (mapOn) {
    // The meshes are prepared the first time; wait for a map of the start pose.
    for (;;) {
      const m = await get('/api/contact-map');
      if (m.status === 'ready' && m.pose_b && Math.abs(m.pose_b[2] - poseAt(0, seconds)[2]) < 1e-9) break;
      await sleep(50);
    }
  }
  await sleep(500);
  const loop0 = (await get('/api/state')).loop;
  const posted = []; // [time, pose]
  const arrivals = []; // { at, seq, pose }
  let dragging = true;
  const t0 = performance.now();
  const poster = (async () => {
    while (performance.now() - t0 < seconds * 1000) {
      const at = performance.now();
      const p = poseAt((at - t0) / 1000, seconds);
      posted.push([at, p]);
      await post('/api/pose', { pose_b: p });
      await sleep(Math.max(0, 1000 / 60 - (performance.now() - at)));
    }
    dragging = false;
  })();
  const fetcher = mapOn && (async () => {
    let seq = (await get('/api/contact-map')).seq;
    while (dragging) {
      const res = await fetch(`${base}/api/contact-map/bands?after=${seq}`);
      const buf = await res.arrayBuffer();
      const at = performance.now();
      const dv = new DataView(buf);
      const s = dv.getUint32(0, true);
      if (s === seq) continue;
      seq = s;
      arrivals.push({ at, seq: s, bytes: buf.byteLength, pose: [0, 1, 2, 3, 4, 5, 6].map((k) => dv.getFloat64(16 + 8 * k, true)) });
    }
  })();
  const times = [];
  const timer = mapOn && (async () => {
    let last = 0;
    while (dragging) {
      const m = (await get('/api/state')).contact_map;
      if (m.seq !== last && m.compute_ms) { times.push([m.compute_ms, m.gaps_ms]); last = m.seq; }
      await sleep(20);
    }
  })();
  await Promise.all([poster, fetcher, timer]);
  const loop1 = (await get('/api/state')).loop;
  const span = (performance.now() - t0) / 1000;
  const out = {
    contact_map: mapOn,
    seconds: Number(span.toFixed(2)),
    poses_posted: posted.length,
    loop: {
      rate_hz: loop1.rate_hz,
      ticks_over_1ms: loop1.over_1ms - loop0.over_1ms,
      ticks: loop1.ticks - loop0.ticks,
      tick_us_p99: loop1.tick_us_p99,
      realtime: loop1.realtime,
    },
  };
  if (mapOn) {
    // A map's latency: from the first post of its pose to its arrival here.
    const lat = [];
    for (const a of arrivals) {
      const p = posted.find(([, pp]) => pp.every((x, k) => Math.abs(x - a.pose[k]) < 1e-9));
      if (p) lat.push(a.at - p[0]);
    }
    const ms = (x) => Number(x.toFixed(1));
    out.maps = arrivals.length;
    out.maps_per_s = ms(arrivals.length / span);
    out.bytes_per_map = arrivals.length ? arrivals[0].bytes : 0;
    out.latency_ms = { p50: ms(q(lat, 0.5)), p90: ms(q(lat, 0.9)), max: ms(Math.max(...lat)), matched: lat.length };
    out.map_ms = { p50: ms(q(times.map((t) => t[0]), 0.5)), p90: ms(q(times.map((t) => t[0]), 0.9)), max: ms(Math.max(...times.map((t) => t[0]))) };
    out.gaps_ms = { p50: ms(q(times.map((t) => t[1]), 0.5)), max: ms(Math.max(...times.map((t) => t[1]))) };
  }
  return out;
}

console.log(JSON.stringify(await drag(false)));
console.log(JSON.stringify(await drag(true)));
await post('/api/contact-map', { on: false });
