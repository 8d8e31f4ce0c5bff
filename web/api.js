// The API client of the page: every request carries the token the user typed in
// (kept for the browser tab), a 401 shows the token form, and a problem+json
// error becomes an Error with its detail.

const KEY = 'shapeflow-token';

export const token = () => sessionStorage.getItem(KEY) || '';
export const setToken = (t) => (t ? sessionStorage.setItem(KEY, t) : sessionStorage.removeItem(KEY));

/** A failed request: status and the detail of the problem document. */
export class ApiError extends Error {
  constructor(status, detail, field) {
    super(detail);
    this.status = status;
    this.field = field;
  }
}

const listeners = new Set();
/** `f(error)` is called on every 401. */
export const onUnauthorized = (f) => listeners.add(f);

function headers(extra) {
  const h = new Headers(extra || {});
  if (token()) h.set('Authorization', `Bearer ${token()}`);
  return h;
}

/** `fetch` with the token; throws ApiError unless the answer is 2xx. */
export async function request(path, options = {}) {
  const r = await fetch(path, { ...options, headers: headers(options.headers) });
  if (r.ok) return r;
  let detail = `${r.status} ${r.statusText}`;
  let field;
  try {
    const p = await r.json();
    detail = p.detail || p.title || detail;
    field = p.errors && p.errors[0] && p.errors[0].field;
  } catch (_) { /* not JSON */ }
  const e = new ApiError(r.status, detail, field);
  if (r.status === 401) listeners.forEach((f) => f(e));
  throw e;
}

export const getJson = async (path) => (await request(path)).json();
export const getBytes = async (path) => (await request(path)).arrayBuffer();

/** An object URL of a binary result (an image), fetched with the token. */
export async function objectUrl(path) {
  return URL.createObjectURL(await (await request(path)).blob());
}

/**
 * Follow the job's Server-Sent Events (fetched as a stream, since EventSource
 * cannot send the token), after iteration `after` (null: from the start):
 * `onEvent(type, data)` for each event; after a dropped connection it reconnects
 * with `Last-Event-ID`, until the `status` event or `signal` aborts.
 */
export async function follow(id, after, onEvent, signal) {
  let last = after;
  for (let attempt = 0; !signal.aborted; attempt++) {
    let done = false;
    try {
      const extra = { Accept: 'text/event-stream' };
      if (last !== null) extra['Last-Event-ID'] = String(last);
      const r = await request(`/v1/jobs/${id}/events`, { headers: extra, signal });
      const reader = r.body.pipeThrough(new TextDecoderStream()).getReader();
      let buffer = '';
      for (;;) {
        const { value, done: end } = await reader.read();
        if (end) break;
        buffer += value;
        let cut;
        while ((cut = buffer.indexOf('\n\n')) >= 0) {
          const block = buffer.slice(0, cut);
          buffer = buffer.slice(cut + 2);
          const event = { type: 'message', data: [], id: null };
          for (const line of block.split('\n')) {
            const colon = line.indexOf(':');
            if (colon === 0) continue; // a comment (keep-alive)
            const [name, value] = colon < 0 ? [line, ''] : [line.slice(0, colon), line.slice(colon + 1).replace(/^ /, '')];
            if (name === 'event') event.type = value;
            else if (name === 'data') event.data.push(value);
            else if (name === 'id') event.id = value;
          }
          if (event.id !== null) last = event.id;
          if (!event.data.length) continue;
          onEvent(event.type, JSON.parse(event.data.join('\n')));
          if (event.type === 'status') done = true;
        }
      }
      attempt = 0;
    } catch (e) {
      if (signal.aborted || e.status === 401 || e.status === 404) return;
    }
    if (done) return;
    await new Promise((ok) => setTimeout(ok, Math.min(5000, 250 * 2 ** attempt)));
  }
}
