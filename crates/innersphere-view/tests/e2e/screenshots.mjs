// The README's pictures, by the end-to-end test's path (headless Chromium, the real page):
// B posed into contact, then the inner spheres of A at a level.
//   node screenshots.mjs URL OUTDIR "tx ty tz qw qx qy qz" LEVEL
import { chromium } from 'playwright-core';

const [url, out, pose, level] = process.argv.slice(2);
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
await browser.close();
console.log(`screenshots in ${out}`);
