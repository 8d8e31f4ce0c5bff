// Small helpers shared by the page's views: elements, the message line, navigation.

/** `el('a', {href}, child, ...)`: an element with properties and children. */
export function el(tag, props = {}, ...children) {
  const e = Object.assign(document.createElement(tag), props);
  e.append(...children.filter((c) => c !== null && c !== undefined));
  return e;
}

/** Show a message above the page (`null` hides it). */
export function say(text, kind = 'error') {
  const box = document.getElementById('alert');
  box.hidden = !text;
  box.textContent = text || '';
  box.className = kind;
}

let router = () => {};
/** The function that renders the page for the current location (set by app.js). */
export const setRouter = (f) => { router = f; };

/** Go to a page of the viewer without reloading it. */
export function go(path) {
  history.pushState(null, '', path);
  router();
}

/** A number with `digits` significant digits ('' for none). */
export const fmt = (x, digits = 6) => (x === null || x === undefined ? '' : Number(x).toPrecision(digits));
