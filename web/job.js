// One job: its status, the energy plot updating live over SSE, the shape in 3D
// with a slider over its checkpoints, the overlay of an image job, and its files.

import { follow, getBytes, getJson, objectUrl, request, token } from './api.js';
import { el, fmt, say } from './dom.js';
import { EnergyPlot } from './plot.js';
import { ShapeView } from './scene.js';

const FINAL = ['successful', 'failed', 'dismissed'];

/** Render job `id` into `main`; returns the function that stops its updates. */
export function showJob(main, id) {
  const abort = new AbortController();
  const status = el('span', { id: 'status', className: 'status' });
  const progress = el('p', { id: 'progress' });
  const message = el('p', { id: 'message', className: 'muted' });
  const cancel = el('button', { type: 'button', textContent: 'Cancel', hidden: true });
  const canvas = el('canvas', { id: 'energy' });
  const shape = el('div', { id: 'shape' });
  const legend = el('div', { id: 'legend' });
  const slider = el('input', { id: 'frame', type: 'range', min: 0, max: 0, value: 0, disabled: true });
  const play = el('button', { type: 'button', textContent: '▶', title: 'play the evolution', disabled: true });
  const frameLabel = el('span', { id: 'frame-label', className: 'muted' });
  const overlay = el('img', { id: 'overlay', alt: 'the contours over the image', hidden: true });
  const files = el('ul', { id: 'files' });
  main.append(
    el('h2', {}, `Job ${id} `, status, ' ', cancel),
    progress, message,
    el('div', { className: 'panels' },
      el('section', {}, el('h3', { textContent: 'Energy' }), canvas),
      el('section', {}, el('h3', { textContent: 'Shape' }), shape, legend,
        el('div', { className: 'slider' }, play, slider, frameLabel)),
      el('section', { id: 'overlay-panel', hidden: true }, el('h3', { textContent: 'Overlay' }), overlay)),
    el('h3', { textContent: 'Result files' }), files);

  const plot = new EnergyPlot(canvas);
  plot.draw();
  let view = null;
  let frames = []; // {label, href, iteration}
  // [iteration, components] of the history's rows, in order: a frame's label
  // says how many components its shape has (a surgery changes it)
  const parts = [];
  const addParts = (rows) => rows.forEach((r) => {
    const last = parts[parts.length - 1];
    if (r.components != null && (!last || r.iteration > last[0])) parts.push([r.iteration, r.components]);
  });
  const partsAt = (iteration) => {
    let n = null;
    for (const [it, c] of parts) { if (iteration != null && it > iteration) break; n = c; }
    return n;
  };
  let following = true; // the slider sits on the newest frame
  const cache = new Map();
  let job = null;

  function showStatus(j) {
    job = j;
    status.textContent = j.status;
    status.className = `status ${j.status}`;
    const p = j.progress;
    progress.textContent = p
      ? `iteration ${p.iteration}, time ${fmt(p.time, 5)}, τ ${fmt(p.tau, 3)}, energy ${fmt(p.energy, 8)}, ${p.vertices} vertices, ${p.components} component(s)`
      : 'waiting for a worker';
    message.textContent = [j.stop_reason && `stop reason: ${j.stop_reason}`, j.message].filter(Boolean).join(' · ');
    cancel.hidden = FINAL.includes(j.status);
  }

  async function showFrame(k) {
    const f = frames[k];
    if (!f) return;
    const n = partsAt(f.iteration);
    frameLabel.textContent = n == null ? f.label : `${f.label}, ${n} component${n === 1 ? '' : 's'}`;
    try {
      if (!cache.has(f.href)) cache.set(f.href, await getBytes(f.href));
      if (!view) view = new ShapeView(shape, legend);
      await view.show(cache.get(f.href));
    } catch (e) {
      if (e.status !== 401) say(`Could not show ${f.href}: ${e.message}`);
    }
  }

  async function showFiles(manifest) {
    files.replaceChildren(...manifest.files.map((f) => {
      const a = el('a', { href: f.href, textContent: f.name, target: '_blank' });
      if (token()) {
        a.addEventListener('click', async (e) => {
          e.preventDefault();
          window.open(await objectUrl(f.href), '_blank');
        });
      }
      return el('li', {}, a, el('span', { className: 'muted', textContent: ` ${f.type}` }));
    }));
    const hasOverlay = manifest.files.some((f) => f.name === 'overlay.png');
    document.getElementById('overlay-panel').hidden = !hasOverlay;
    overlay.hidden = !hasOverlay;
    // fetched again only when the state it shows changed
    const key = `${frames.length} ${manifest.final}`;
    if (hasOverlay && key !== overlayKey) {
      overlayKey = key;
      const url = await objectUrl(`/v1/jobs/${id}/results/overlay.png`);
      if (overlay.src.startsWith('blob:')) URL.revokeObjectURL(overlay.src);
      overlay.src = url;
    }
  }

  let overlayKey = null;
  let loading = null;
  let again = false;
  /** Read the manifest and the checkpoints; show the newest frame if following. */
  async function refreshResults() {
    if (loading) { again = true; return loading; }
    loading = (async () => {
      try {
        const manifest = await getJson(`/v1/jobs/${id}/results`);
        const { checkpoints } = await getJson(`/v1/jobs/${id}/checkpoints`);
        frames = checkpoints.map((c) => ({
          label: `checkpoint: iteration ${c.iteration}, time ${fmt(c.time, 5)}`, href: c.href, iteration: c.iteration,
        }));
        if (manifest.final && checkpoints.length) {
          frames.push({ label: 'result (shape.glb)', href: `/v1/jobs/${id}/results/shape.glb`, iteration: null });
        }
        slider.max = String(Math.max(frames.length - 1, 0));
        slider.disabled = play.disabled = frames.length < 2;
        // the list first: drawing the newest frame waits for its download
        await showFiles(manifest);
        if (frames.length && following) {
          slider.value = slider.max;
          await showFrame(frames.length - 1);
        }
      } catch (e) {
        if (e.status !== 401) say(`Could not read the results: ${e.message}`);
      }
    })();
    await loading;
    loading = null;
    if (again) { again = false; await refreshResults(); }
  }

  slider.addEventListener('input', () => {
    following = Number(slider.value) === frames.length - 1;
    showFrame(Number(slider.value));
  });
  let playing = null;
  play.addEventListener('click', () => {
    if (playing) { clearInterval(playing); playing = null; play.textContent = '▶'; return; }
    play.textContent = '⏸';
    let k = 0;
    playing = setInterval(async () => {
      slider.value = String(k);
      following = k === frames.length - 1;
      await showFrame(k);
      if (++k >= frames.length) { clearInterval(playing); playing = null; play.textContent = '▶'; }
    }, 400);
  });
  cancel.addEventListener('click', async () => {
    try {
      showStatus(await (await request(`/v1/jobs/${id}/cancel`, { method: 'POST' })).json());
    } catch (e) {
      if (e.status !== 401) say(`Could not cancel: ${e.message}`);
    }
  });

  (async () => {
    try {
      showStatus(await getJson(`/v1/jobs/${id}`));
      const { history } = await getJson(`/v1/jobs/${id}/energy`);
      plot.add(history);
      addParts(history);
    } catch (e) {
      if (e.status !== 401) say(e.status === 404 ? `There is no job ${id}.` : `Could not read job ${id}: ${e.message}`);
      return;
    }
    await refreshResults();
    if (FINAL.includes(job.status)) return;
    let last = 0;
    const after = plot.points.length ? plot.points[plot.points.length - 1][0] : null;
    await follow(id, after, (type, data) => {
      if (type === 'progress') {
        plot.add([data]);
        addParts([data]);
        showStatus({ ...job, status: 'running', progress: data });
        if (Date.now() - last > 1500) { last = Date.now(); refreshResults(); }
      } else if (type === 'status') {
        showStatus(data);
        refreshResults();
      }
    }, abort.signal);
  })();

  return () => {
    abort.abort();
    if (playing) clearInterval(playing);
  };
}
