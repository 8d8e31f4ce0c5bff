// The job list (status and live progress, refreshed every second) and the form
// that submits a new job.

import { getJson } from './api.js';
import { el, fmt, say } from './dom.js';
import { submitForm } from './form.js';

function progressText(job) {
  const p = job.progress;
  if (!p) return '';
  return `iteration ${p.iteration}, t = ${fmt(p.time, 4)}, E = ${fmt(p.energy)}`;
}

function row(job) {
  const link = el('a', { href: `/jobs/${job.id}`, textContent: job.id.slice(0, 8) });
  link.dataset.local = '';
  const tr = el('tr', {},
    el('td', {}, link),
    el('td', { className: `status ${job.status}`, textContent: job.status }),
    el('td', { textContent: progressText(job) }),
    el('td', { textContent: job.stop_reason || '' }),
    el('td', { textContent: job.created ? new Date(job.created).toLocaleString() : '' }));
  tr.dataset.id = job.id;
  return tr;
}

/** Render the list and the form into `main`; returns the function that stops the refresh. */
export function showJobs(main) {
  const body = el('tbody');
  const table = el('table', { id: 'jobs' },
    el('thead', {}, el('tr', {}, ...['job', 'status', 'progress', 'stop reason', 'created'].map((h) => el('th', { textContent: h })))),
    body);
  const empty = el('p', { className: 'muted', textContent: 'No jobs yet: submit one below.', hidden: true });
  main.append(el('h2', { textContent: 'Jobs' }), table, empty, submitForm());
  let timer = null;
  let stopped = false;
  async function refresh() {
    try {
      const { jobs } = await getJson('/v1/jobs?limit=50');
      body.replaceChildren(...jobs.map(row));
      empty.hidden = jobs.length > 0;
    } catch (e) {
      if (e.status !== 401) say(`Could not list the jobs: ${e.message}`);
      return; // after a 401 the token form reloads the page
    }
    if (!stopped) timer = setTimeout(refresh, 1000);
  }
  refresh();
  return () => { stopped = true; clearTimeout(timer); };
}
