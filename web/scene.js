// The shape in 3D: a glTF result (shape.glb or one checkpoint) drawn by three.js,
// with orbit controls and the legend of its colour map (the node's extras.colors).

import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { el, fmt } from './dom.js';

const FIELDS = { _CURVATURE: 'curvature', _NORMAL_VELOCITY: 'normal velocity' };

export class ShapeView {
  /** Draw into `container`; the legend goes into `legend`. */
  constructor(container, legend) {
    this.container = container;
    this.legend = legend;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.append(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xf2f2f2);
    this.camera = new THREE.PerspectiveCamera(35, 1, 1e-3, 1e4);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 2.0));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(1, 2, 3);
    this.camera.add(sun);
    this.scene.add(this.camera);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.render());
    this.model = null;
    this.framed = false;
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const w = this.container.clientWidth || 480;
    const h = this.container.clientHeight || 360;
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }

  /** Show the glTF binary `bytes` in place of the previous one. */
  async show(bytes) {
    const gltf = await new GLTFLoader().parseAsync(bytes, '');
    if (this.model) this.scene.remove(this.model);
    this.model = gltf.scene;
    this.scene.add(this.model);
    let drawn = 0;
    let colors = null;
    this.model.traverse((o) => {
      if (o.isMesh || o.isLine) drawn += 1;
      if (o.isMesh && o.material) o.material.side = THREE.DoubleSide;
      if (!colors && o.userData && o.userData.colors) colors = o.userData.colors;
    });
    if (!this.framed) this.frame();
    this.showLegend(colors);
    this.render();
    this.container.dataset.meshes = String(drawn);
    this.container.dataset.frames = String(Number(this.container.dataset.frames || 0) + 1);
    return drawn;
  }

  /** Point the camera at the model: from +z for a plane curve, obliquely for a surface. */
  frame() {
    const box = new THREE.Box3().setFromObject(this.model);
    if (box.isEmpty()) return;
    const size = box.getSize(new THREE.Vector3());
    const center = box.getCenter(new THREE.Vector3());
    const radius = Math.max(size.length() / 2, 1e-6);
    const distance = radius / Math.sin((this.camera.fov * Math.PI) / 360) * 1.1;
    const flat = size.z < 0.05 * Math.max(size.x, size.y, 1e-12); // curves: z = 0, ribbons a little above
    const dir = flat ? new THREE.Vector3(0, 0, 1) : new THREE.Vector3(1, 0.8, 1.4).normalize();
    this.camera.position.copy(center).addScaledVector(dir, distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(center);
    this.controls.update();
    this.framed = true;
  }

  showLegend(c) {
    if (!c) { this.legend.replaceChildren(); return; }
    this.legend.replaceChildren(
      el('span', { className: 'field', textContent: FIELDS[c.field] || c.field }),
      el('span', { textContent: fmt(c.blue, 4) }),
      el('span', { className: 'bar', title: `${c.map}, white at the median ${fmt(c.white, 6)}` }),
      el('span', { textContent: fmt(c.red, 4) }));
  }
}
