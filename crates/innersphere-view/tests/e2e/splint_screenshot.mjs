// The splint picture of docs/SPLINT.md: `ist view` with a splint, B at the splint's pose
// (given to the server), the page as it opens, then A hidden to show the wafer's upper
// imprints.   node splint_screenshot.mjs URL OUTDIR
import { chromium } from 'playwright-core';

const [url, out] = process.argv.slice(2);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--use-gl=swiftshader', '--enable-unsafe-swiftshader'],
});
const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
await page.goto(url);
await page.waitForFunction(() => window.__ist && window.__ist.ready, null, { timeout: 300000 });
await page.waitForFunction(() => !document.getElementById('splint-panel').hidden, null, { timeout: 300000 });
await page.waitForTimeout(3000);
await page.screenshot({ path: `${out}/splint.png` });
await browser.close();
console.log(`screenshot in ${out}`);
