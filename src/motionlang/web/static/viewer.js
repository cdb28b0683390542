// A skeleton viewer on a 2D canvas: perspective projection of joint positions (metres,
// Y up), orbit by dragging, zoom by the wheel, play/pause and scrub. No WebGL, so that
// it draws the same in every browser, headless ones included.
"use strict";

class SkeletonViewer {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.motion = null;
    this.time = 0;
    this.playing = true;
    this.azimuth = 0.6;     // radians about +Y, 0 = looking at the body's front (+Z side)
    this.elevation = 0.25;  // radians above the floor
    this.zoom = 1;
    this.onFrame = null;    // called with (time, frame) after each drawing
    this.onFirstDraw = null;
    this.last = null;
    this._bindInput();
    requestAnimationFrame((t) => this._tick(t));
  }

  setMotion(view) {
    const f = new Float32Array(view.frames);
    const J = view.n_joints;
    const T = view.n_frames;
    let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < T * J; i++) {
      for (let c = 0; c < 3; c++) {
        lo[c] = Math.min(lo[c], f[3 * i + c]);
        hi[c] = Math.max(hi[c], f[3 * i + c]);
      }
    }
    const children = new Array(J).fill(0);
    view.parents.forEach((p) => { if (p >= 0) children[p]++; });
    this.motion = {
      frames: f, J: J, T: T, fps: view.fps, parents: view.parents, sides: view.sides,
      floor: view.floor, lo: lo, hi: hi, leaves: children.map((n) => n === 0),
      height: Math.max(hi[1] - view.floor, 0.1),
    };
    this.time = 0;
    this.firstDrawPending = true;
    this.playing = true;
  }

  get duration() { return this.motion ? (this.motion.T - 1) / this.motion.fps : 0; }

  frameAt(t) { return this.motion ? Math.min(this.motion.T - 1, Math.round(t * this.motion.fps)) : 0; }

  seek(t) { this.time = Math.max(0, Math.min(t, this.duration)); this.draw(); }

  toggle() { this.playing = !this.playing; }

  _bindInput() {
    let drag = null;
    this.canvas.addEventListener("pointerdown", (e) => {
      drag = { x: e.clientX, y: e.clientY, az: this.azimuth, el: this.elevation };
      this.canvas.setPointerCapture(e.pointerId);
    });
    this.canvas.addEventListener("pointermove", (e) => {
      if (!drag) return;
      this.azimuth = drag.az - (e.clientX - drag.x) * 0.01;
      this.elevation = Math.max(-0.2, Math.min(1.45, drag.el + (e.clientY - drag.y) * 0.01));
      this.draw();
    });
    const end = () => { drag = null; };
    this.canvas.addEventListener("pointerup", end);
    this.canvas.addEventListener("pointercancel", end);
    this.canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.zoom = Math.max(0.2, Math.min(5, this.zoom * Math.exp(e.deltaY * 0.001)));
      this.draw();
    }, { passive: false });
  }

  _tick(now) {
    if (this.last !== null && this.playing && this.motion) {
      this.time += (now - this.last) / 1000;
      if (this.time > this.duration) this.time = 0;
    }
    this.last = now;
    if (this.motion) this.draw();
    requestAnimationFrame((t) => this._tick(t));
  }

  // the pose at time t, interpolated between the two nearest frames
  pose(t) {
    const m = this.motion;
    const x = Math.min(t * m.fps, m.T - 1);
    const a = Math.floor(x), b = Math.min(a + 1, m.T - 1), w = x - a;
    const out = new Float32Array(m.J * 3);
    for (let i = 0; i < m.J * 3; i++) {
      out[i] = (1 - w) * m.frames[a * m.J * 3 + i] + w * m.frames[b * m.J * 3 + i];
    }
    return out;
  }

  // the camera follows the root over the floor, so that a long walk stays in view and the
  // grid passing under the feet shows whether they slide
  _camera(p) {
    const m = this.motion;
    const target = [p[0], m.floor + m.height * 0.45, p[2]];
    const dist = 3.2 * m.height * this.zoom;
    const ce = Math.cos(this.elevation);
    const eye = [target[0] + dist * Math.sin(this.azimuth) * ce,
                 target[1] + dist * Math.sin(this.elevation),
                 target[2] + dist * Math.cos(this.azimuth) * ce];
    const f = norm(sub(target, eye));
    const r = norm(cross(f, [0, 1, 0]));
    const u = cross(r, f);
    const focal = 0.5 * this.canvas.height / Math.tan(0.5 * 0.8);
    return { eye, f, r, u, focal };
  }

  _project(cam, p) {
    const d = sub(p, cam.eye);
    const z = Math.max(dot(d, cam.f), 0.05);
    return [this.canvas.width / 2 + cam.focal * dot(d, cam.r) / z,
            this.canvas.height / 2 - cam.focal * dot(d, cam.u) / z, z];
  }

  draw() {
    const ctx = this.ctx, m = this.motion, W = this.canvas.width, H = this.canvas.height;
    ctx.fillStyle = "#fafafa";
    ctx.fillRect(0, 0, W, H);
    if (!m) return;
    const p = this.pose(this.time);
    const cam = this._camera(p);
    this._floor(cam);
    const at = (j) => [p[3 * j], p[3 * j + 1], p[3 * j + 2]];
    // the shadow on the floor: a figure that floats or sinks shows it at once
    ctx.strokeStyle = "rgba(0,0,0,0.18)";
    ctx.lineWidth = 5;
    ctx.lineCap = "round";
    for (let j = 0; j < m.J; j++) {
      const q = m.parents[j];
      if (q < 0) continue;
      const a = this._project(cam, [p[3 * j], m.floor, p[3 * j + 2]]);
      const b = this._project(cam, [p[3 * q], m.floor, p[3 * q + 2]]);
      line(ctx, a, b);
    }
    // bones far to near, coloured by side: left blue, right orange
    const bones = [];
    for (let j = 0; j < m.J; j++) {
      const q = m.parents[j];
      if (q < 0) continue;
      const a = this._project(cam, at(j)), b = this._project(cam, at(q));
      bones.push({ a, b, z: (a[2] + b[2]) / 2, side: m.sides[j], leaf: m.leaves[j] });
    }
    bones.sort((x, y) => y.z - x.z);
    const scale = cam.focal / Math.max(dot(sub([p[0], p[1], p[2]], cam.eye), cam.f), 0.1);
    for (const bone of bones) {
      ctx.strokeStyle = bone.side === "L" ? "#2a6fdb" : bone.side === "R" ? "#e07b22" : "#444";
      ctx.lineWidth = Math.max(2, 0.035 * scale);
      line(ctx, bone.a, bone.b);
      if (bone.leaf && bone.side === "" && bone.a[1] < bone.b[1]) {   // the head
        ctx.fillStyle = "#444";
        ctx.beginPath();
        ctx.arc(bone.a[0], bone.a[1], Math.max(4, 0.09 * scale), 0, 2 * Math.PI);
        ctx.fill();
      }
    }
    const frame = this.frameAt(this.time);
    if (this.onFrame) this.onFrame(this.time, frame);
    if (this.firstDrawPending) {
      this.firstDrawPending = false;
      if (this.onFirstDraw) this.onFirstDraw();
    }
  }

  _floor(cam) {
    const m = this.motion, ctx = this.ctx, step = 0.5;
    const x0 = Math.floor((m.lo[0] - 1) / step) * step, x1 = Math.ceil((m.hi[0] + 1) / step) * step;
    const z0 = Math.floor((m.lo[2] - 1) / step) * step, z1 = Math.ceil((m.hi[2] + 1) / step) * step;
    ctx.strokeStyle = "#d6d6d6";
    ctx.lineWidth = 1;
    for (let x = x0; x <= x1 + 1e-9; x += step) {
      line(ctx, this._project(cam, [x, m.floor, z0]), this._project(cam, [x, m.floor, z1]));
    }
    for (let z = z0; z <= z1 + 1e-9; z += step) {
      line(ctx, this._project(cam, [x0, m.floor, z]), this._project(cam, [x1, m.floor, z]));
    }
    // the root's path over the whole take, on the floor
    ctx.strokeStyle = "rgba(120,120,160,0.5)";
    ctx.beginPath();
    for (let t = 0; t < m.T; t++) {
      const i = t * m.J * 3;
      const s = this._project(cam, [m.frames[i], m.floor, m.frames[i + 2]]);
      if (t === 0) ctx.moveTo(s[0], s[1]); else ctx.lineTo(s[0], s[1]);
    }
    ctx.stroke();
  }
}

function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
function norm(a) { const n = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / n, a[1] / n, a[2] / n]; }
function line(ctx, a, b) { ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke(); }

window.SkeletonViewer = SkeletonViewer;
