// The submit form: a spec as JSON text (typed, or one of the examples), and input
// files dropped on it. Each file is sent as the multipart part named in its box
// (the first "input:NAME" of the spec still without a file, else the file's stem);
// the spec refers to it as "input:NAME".

import { getJson, request } from './api.js';
import { el, go, say } from './dom.js';

/** The stem of a file name: `star.png` → `star`. */
const stem = (name) => name.replace(/\.[^.]*$/, '').replace(/\.nii$/, '');

export function submitForm() {
  const examples = el('select', { id: 'example' }, el('option', { value: '', textContent: 'an example…' }));
  const spec = el('textarea', { id: 'spec', rows: 12, spellcheck: false,
    placeholder: '{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1}}' });
  const files = el('ul', { id: 'files' });
  const needed = el('p', { className: 'muted' });
  const drop = el('div', { id: 'drop', textContent: 'Drop input files here (or click to choose)' });
  const picker = el('input', { type: 'file', multiple: true, hidden: true });
  const send = el('button', { type: 'submit', textContent: 'Submit job' });
  const form = el('form', { id: 'submit' },
    el('h2', { textContent: 'New job' }),
    el('label', {}, 'Start from ', examples),
    spec, needed, drop, picker, files, send);

  const chosen = new Map(); // part name → File
  function listFiles() {
    files.replaceChildren(...[...chosen].map(([name, file]) => {
      const box = el('input', { value: name, size: 12, title: 'the part name: the spec says "input:NAME"' });
      box.addEventListener('change', () => {
        chosen.delete(name);
        chosen.set(box.value.trim(), file);
        listFiles();
      });
      const remove = el('button', { type: 'button', textContent: '×', title: 'remove' });
      remove.addEventListener('click', () => { chosen.delete(name); listFiles(); });
      return el('li', {}, 'input:', box, ` ← ${file.name} (${file.size} bytes) `, remove);
    }));
  }
  /** Each file takes the first "input:NAME" of the spec that no file has yet, else its stem. */
  function add(list) {
    const wanted = [...spec.value.matchAll(/"input:([^"]+)"/g)].map((m) => m[1]);
    for (const f of list) {
      const free = wanted.find((n) => !chosen.has(n));
      chosen.set(free || stem(f.name), f);
    }
    listFiles();
  }
  drop.addEventListener('click', () => picker.click());
  picker.addEventListener('change', () => add(picker.files));
  drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
  drop.addEventListener('dragleave', () => drop.classList.remove('over'));
  drop.addEventListener('drop', (e) => {
    e.preventDefault();
    drop.classList.remove('over');
    add(e.dataTransfer.files);
  });

  let list = [];
  getJson('/ui/examples.json').then((all) => {
    list = all;
    examples.append(...all.map((x, k) => el('option', { value: String(k), textContent: x.name })));
  }).catch(() => {});
  examples.addEventListener('change', () => {
    const x = list[Number(examples.value)];
    if (!x) return;
    spec.value = x.spec;
    needed.textContent = x.inputs.length
      ? `This example needs the file${x.inputs.length > 1 ? 's' : ''} ${x.inputs.map((n) => `input:${n}`).join(', ')} (examples/data/ in the repository).`
      : '';
  });

  form.addEventListener('submit', async (e) => {
    e.preventDefault();
    say(null);
    let body;
    const headers = {};
    if (chosen.size) {
      body = new FormData();
      body.append('spec', spec.value);
      for (const [name, file] of chosen) body.append(name, file, file.name);
    } else {
      body = spec.value;
      headers['Content-Type'] = 'application/json';
    }
    send.disabled = true;
    try {
      const job = await (await request('/v1/jobs', { method: 'POST', body, headers })).json();
      go(`/jobs/${job.id}`);
    } catch (err) {
      if (err.status !== 401) say(`The job was not accepted: ${err.message}`);
    } finally {
      send.disabled = false;
    }
  });
  return form;
}
