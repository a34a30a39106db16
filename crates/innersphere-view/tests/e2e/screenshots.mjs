// The README's pictures, by the end-to-end test's path (headless Chromium, the real page):
// B posed into contact, then the inner spheres of A at a level, then (when a contact-map
// pose is given and the page offers the mode) the contact map at that pose, B shown alone.
//   node screenshots.mjs URL OUTDIR "tx ty tz qw qx qy qz" LEVEL ["tx ty tz qw qx qy qz"]
import { chromium } from 'playwright-core';

const [url, out, pose, level, mapPose] = process.argv.slice(2);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--use-gl=swiftshader', '--enable-unsafe-swiftshader'],
});
const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
await page.goto(url);
await page.waitForFunction(() => window.__ist && window.__ist.ready, null, { timeout: 120000 });
await page.evaluate((p) => window.__ist.setPose(p.split(/\s+/).map(Number)), pose);
await page.waitForFunction(() => window.__ist.state && window.__ist.state.contact, null, { timeout: 30000 });
await page.waitForTimeout(1500);
await page.screenshot({ path: `${out}/contact.png` });
await page.check('#show-spheres');
await page.fill('#level', String(level));
await page.dispatchEvent('#level', 'input');
await page.waitForTimeout(4000);
await page.screenshot({ path: `${out}/spheres.png` });
if (mapPose && await page.evaluate(() => window.__ist.contactMap.available)) {
  await page.uncheck('#show-spheres');
  const p7 = mapPose.split(/\s+/).map(Number);
  await page.evaluate((p) => window.__ist.setPose(p), p7);
  await page.check('#contact-map');
  // The map of that pose on the meshes (the first map waits for the meshes to be prepared).
  await page.waitForFunction((p) => {
    const c = window.__ist.contactMap;
    return c.pose && c.pose.every((x, k) => Math.abs(x - p[k]) < 1e-9)
      && c.teeth !== null === (window.__ist.info.contact_map.teeth.a || window.__ist.info.contact_map.teeth.b);
  }, p7, { timeout: 120000 });
  // B alone: its surface that faces A (the map is of the pose with A there).
  await page.selectOption('#cm-show', 'b');
  await page.mouse.move(5, 5);
  await page.waitForTimeout(4000);
  await page.screenshot({ path: `${out}/contact-map.png` });
}
await browser.close();
console.log(`screenshots in ${out}`);
