// Drive the viewer page in headless Chromium (playwright-core, Debian's chromium;
// run by tests/service/viewer.rs): with the server's token unknown, the page must show the
// 401 message; with the token typed in, submit SPEC through the form, wait for the
// job to end, and report what the page drew (energy points and ink, rendered
// meshes and ink of the 3D canvas). Then an image job: the example EXAMPLE picked
// from the list, IMAGE dropped on the form, its overlay shown. Screenshots go to
// OUT_DIR (job.png, image-job.png). With SURGERY_SPEC, a 3D job whose number of
// components changes: every frame of its slider drawn in turn, with its label.
//
//   node scripts/viewer_browser.mjs URL TOKEN SPEC_FILE OUT_DIR EXAMPLE IMAGE [SURGERY_SPEC]
import { chromium } from 'playwright-core';
import { readFileSync } from 'node:fs';
import { basename, join } from 'node:path';

const [base, token, specFile, shots, example, imageFile, surgeryFile] = process.argv.slice(2);
const spec = readFileSync(specFile, 'utf8');
const FINAL = ['successful', 'failed', 'dismissed'];

/** Submit the form and wait for the page of the new job (none of `seen`); its id. */
async function submitted(page, seen) {
  await page.click('#submit button[type=submit]');
  await page.waitForURL((u) => /\/jobs\/[0-9a-f-]+$/.test(u.pathname) && !seen.includes(u.pathname.split('/').pop()),
    { timeout: 20000 });
  return page.url().split('/').pop();
}

/** Wait for the job shown to end (within `timeout` ms); its status. */
async function finished(page, timeout) {
  await page.waitForFunction((final) => final.includes(document.querySelector('#status')?.textContent),
    FINAL, { timeout });
  return page.textContent('#status');
}

/** Wait for the final frame (shape.glb) to be drawn. */
async function resultDrawn(page) {
  await page.waitForFunction(() => document.querySelector('#frame-label')?.textContent.startsWith('result')
    && Number(document.querySelector('#shape')?.dataset.meshes) > 0, null, { timeout: 60000 });
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
const report = {};
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 1000 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => m.type() === 'error' && !m.text().includes('401') && errors.push(m.text()));
  // pixels of a canvas that differ from its corner (the background)
  await page.addInitScript(() => {
    window.ink = (canvas) => {
      const c = document.createElement('canvas');
      c.width = canvas.width; c.height = canvas.height;
      const g = c.getContext('2d');
      g.drawImage(canvas, 0, 0);
      const d = g.getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let k = 0; k < d.length; k += 4) {
        if (Math.abs(d[k] - d[0]) + Math.abs(d[k + 1] - d[1]) + Math.abs(d[k + 2] - d[2]) + Math.abs(d[k + 3] - d[3]) > 24) n++;
      }
      return n;
    };
  });
  await page.goto(base + '/');
  // no token yet: the list answers 401 and the page says so
  await page.waitForSelector('#alert:not([hidden])', { timeout: 20000 });
  report.unauthorized = await page.textContent('#alert');
  report.tokenFormShown = await page.isVisible('#token-form');
  await page.fill('#token', token);
  await page.click('#token-form button');
  await page.waitForSelector('#jobs', { timeout: 20000 });
  await page.fill('#spec', spec);
  report.job = await submitted(page, []);
  report.status = await finished(page, 120000);
  // the final frame (shape.glb) drawn, the slider over every frame
  await resultDrawn(page);
  Object.assign(report, await page.evaluate(() => {
    const ink = window.ink;
    const shape = document.querySelector('#shape');
    return {
      points: Number(document.querySelector('#energy').dataset.points),
      energyInk: ink(document.querySelector('#energy')),
      meshes: Number(shape.dataset.meshes),
      shapeInk: ink(shape.querySelector('canvas')),
      frames: Number(document.querySelector('#frame').max) + 1,
      legend: document.querySelector('#legend').textContent,
      files: [...document.querySelectorAll('#files a')].map((a) => a.textContent),
    };
  }));
  await page.screenshot({ path: join(shots, 'job.png'), fullPage: true });

  // an image job: an example from the list, the image dropped on the form
  await page.click('a.brand');
  await page.waitForSelector(`#example option:text("${example}")`, { state: 'attached', timeout: 20000 });
  await page.selectOption('#example', { label: example });
  const bytes = readFileSync(imageFile).toString('base64');
  await page.evaluate(([name, b64]) => {
    const data = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const dt = new DataTransfer();
    dt.items.add(new File([data], name, { type: 'image/png' }));
    const drop = document.querySelector('#drop');
    drop.dispatchEvent(new DragEvent('dragover', { dataTransfer: dt, bubbles: true, cancelable: true }));
    drop.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
  }, [basename(imageFile), bytes]);
  report.dropped = await page.inputValue('#files li input');
  report.imageJob = await submitted(page, [report.job]);
  report.imageStatus = await finished(page, 120000);
  await page.waitForFunction(() => document.querySelector('#overlay')?.complete
    && document.querySelector('#overlay').naturalWidth > 0
    && Number(document.querySelector('#shape')?.dataset.meshes) > 0, null, { timeout: 60000 });
  report.overlayWidth = await page.evaluate(() => document.querySelector('#overlay').naturalWidth);
  await page.screenshot({ path: join(shots, 'image-job.png'), fullPage: true });

  if (surgeryFile) {
    // a job whose surfaces merge (or pinch): each frame drawn, and its label
    await page.click('a.brand');
    await page.waitForSelector('#jobs', { timeout: 20000 });
    await page.fill('#spec', readFileSync(surgeryFile, 'utf8'));
    report.surgeryJob = await submitted(page, [report.job, report.imageJob]);
    report.surgeryStatus = await finished(page, 180000);
    await resultDrawn(page);
    const count = Number(await page.getAttribute('#frame', 'max')) + 1;
    report.surgeryFrames = [];
    for (let k = 0; k < count; k++) {
      const drawn = Number(await page.getAttribute('#shape', 'data-frames'));
      await page.evaluate((k) => {
        const s = document.querySelector('#frame');
        s.value = String(k);
        s.dispatchEvent(new Event('input'));
      }, k);
      await page.waitForFunction((n) => Number(document.querySelector('#shape').dataset.frames) > n, drawn,
        { timeout: 20000 });
      report.surgeryFrames.push(await page.evaluate(() => ({
        label: document.querySelector('#frame-label').textContent,
        meshes: Number(document.querySelector('#shape').dataset.meshes),
        ink: window.ink(document.querySelector('#shape canvas')),
      })));
    }
    await page.screenshot({ path: join(shots, 'surgery-job.png'), fullPage: true });
  }
  report.errors = errors;
} finally {
  await browser.close();
}
console.log(JSON.stringify(report));
