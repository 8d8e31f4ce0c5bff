// The energy plot: energy against iteration on a canvas, redrawn as points arrive.

import { fmt } from './dom.js';

export class EnergyPlot {
  constructor(canvas) {
    this.canvas = canvas;
    this.points = []; // [iteration, energy]
  }

  /** Add history rows ({iteration, energy}) and redraw. */
  add(rows) {
    for (const r of rows) {
      const last = this.points[this.points.length - 1];
      if (!last || r.iteration > last[0]) this.points.push([r.iteration, r.energy]);
    }
    this.draw();
  }

  draw() {
    const c = this.canvas;
    const ratio = window.devicePixelRatio || 1;
    const w = c.clientWidth || 480;
    const h = c.clientHeight || 240;
    c.width = Math.round(w * ratio);
    c.height = Math.round(h * ratio);
    const g = c.getContext('2d');
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.clearRect(0, 0, w, h);
    g.font = '12px system-ui, sans-serif';
    g.fillStyle = '#555';
    c.dataset.points = String(this.points.length);
    if (!this.points.length) {
      g.fillText('no iteration yet', 10, h / 2);
      return;
    }
    const left = 78, right = 12, top = 12, bottom = 28;
    const xs = this.points.map((p) => p[0]);
    const ys = this.points.map((p) => p[1]).filter(Number.isFinite);
    const [x0, x1] = [xs[0], Math.max(xs[xs.length - 1], xs[0] + 1)];
    let [y0, y1] = [Math.min(...ys), Math.max(...ys)];
    if (y1 - y0 < 1e-12 * Math.max(1, Math.abs(y0))) { y0 -= 0.5; y1 += 0.5; }
    const px = (x) => left + ((x - x0) / (x1 - x0)) * (w - left - right);
    const py = (y) => top + ((y1 - y) / (y1 - y0)) * (h - top - bottom);
    g.strokeStyle = '#bbb';
    g.beginPath();
    g.moveTo(left, top);
    g.lineTo(left, h - bottom);
    g.lineTo(w - right, h - bottom);
    g.stroke();
    g.textAlign = 'right';
    g.fillText(fmt(y1, 5), left - 6, top + 8);
    g.fillText(fmt(y0, 5), left - 6, h - bottom);
    g.textAlign = 'center';
    g.fillText(String(x0), left, h - 8);
    g.fillText(String(x1), w - right - 10, h - 8);
    g.fillText('iteration', (left + w - right) / 2, h - 8);
    g.strokeStyle = '#1f5fbf';
    g.lineWidth = 1.5;
    g.beginPath();
    this.points.forEach(([x, y], k) => (k ? g.lineTo(px(x), py(y)) : g.moveTo(px(x), py(y))));
    g.stroke();
  }
}
