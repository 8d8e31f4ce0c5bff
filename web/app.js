// The viewer page: `/` lists the jobs and submits new ones, `/jobs/{id}` shows one
// job (docs/viewer.md). Plain ES modules served by the binary; no build step.

import { onUnauthorized, setToken, token } from './api.js';
import { showJobs } from './jobs.js';
import { showJob } from './job.js';
import { go, say, setRouter } from './dom.js';

const main = document.getElementById('main');
const tokenForm = document.getElementById('token-form');

let stop = () => {};

function route() {
  stop();
  say(null);
  main.replaceChildren();
  const m = location.pathname.match(/^\/jobs\/([^/]+)$/);
  stop = m ? showJob(main, decodeURIComponent(m[1])) : showJobs(main);
}

onUnauthorized(() => {
  tokenForm.hidden = false;
  say(token()
    ? 'The server refused this token (401 Unauthorized). Enter the token the server was started with (--token).'
    : 'This server needs a token (401 Unauthorized): enter the one it was started with (--token).');
  document.getElementById('token').focus();
});

tokenForm.addEventListener('submit', (e) => {
  e.preventDefault();
  setToken(document.getElementById('token').value.trim());
  tokenForm.hidden = true;
  route();
});

setRouter(route);
addEventListener('popstate', route);
document.addEventListener('click', (e) => {
  const a = e.target.closest('a[data-local]');
  if (a && !e.ctrlKey && !e.metaKey && e.button === 0) {
    e.preventDefault();
    go(a.getAttribute('href'));
  }
});
document.getElementById('server').textContent = location.host;
route();
