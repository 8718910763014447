// The page of an nhdyn report (io/report.hpp, docs/report.md). NHDYN holds the run: times t, the
// plots' series and, per shown row, the positions and rotations of the scene's shapes computed by
// the library (symbolic/visual.hpp), so this script only places shapes and draws curves. THREE
// (Debian's libjs-three) draws the scene, katex (libjs-katex) the equations.
(function () {
  "use strict";
  const D = NHDYN;
  const T = D.t;
  const frames = T.length;
  const api = { ready: false, frame: 0, frames: frames };
  window.nhdyn = api;

  // ---- Page ------------------------------------------------------------------------------------
  const el = (tag, attrs, parent) => {
    const e = document.createElement(tag);
    for (const k in attrs || {}) {
      if (k === "text") e.textContent = attrs[k];
      else e.setAttribute(k, attrs[k]);
    }
    if (parent) parent.appendChild(e);
    return e;
  };
  const header = el("header", {}, document.body);
  el("h1", { text: D.title }, header);
  const main = el("div", { id: "main" }, document.body);
  const left = el("div", { id: "left" }, main);
  const right = el("div", { id: "right" }, main);
  const view = el("div", { id: "view" }, left);
  const controls = el("div", { id: "controls" }, left);
  const play = el("button", { id: "play", text: "Pause" }, controls);
  const speed = el("select", { id: "speed", title: "speed" }, controls);
  for (const s of [0.1, 0.25, 0.5, 1, 2, 4, 10]) {
    const o = el("option", { value: String(s), text: s + "x" }, speed);
    if (s === 1) o.selected = true;
  }
  const slider = el("input", { id: "slider", type: "range", min: "0", max: String(frames - 1), value: "0", step: "1" },
                    controls);
  const timeLabel = el("span", { id: "time" }, controls);
  const follow = el("select", { id: "follow", title: "camera follows" }, controls);
  el("option", { value: "-1", text: "whole motion" }, follow);
  el("option", { value: "-2", text: "follow the bodies" }, follow);
  // Kinds that are not a moving thing to follow: axes, a contact point's path, a ground.
  const fixedKinds = ["frame", "track", "terrain", "surface", "plane"];
  D.scene.shapes.forEach((s, i) => {
    if (!fixedKinds.includes(s.kind)) el("option", { value: String(i), text: "follow " + s.name }, follow);
  });
  if (D.note) el("div", { id: "note", text: D.note }, left);
  el("h2", { text: "Summary" }, left);
  const summary = el("table", { class: "summary" }, left);
  for (const [k, v] of D.summary) {
    const tr = el("tr", {}, summary);
    el("td", { text: k }, tr);
    el("td", { text: v }, tr);
  }

  // ---- Scene -----------------------------------------------------------------------------------
  const S = D.scene;
  const stride = S.stride;
  const value = (f, i) => S.values[f * stride + i];
  // The largest distance of a shape's points from its origin (a path or a ground: 0, its points
  // are those of the contact it follows).
  const reach = (s) => {
    if (s.kind === "frame" || s.kind === "track" || s.kind === "terrain" || s.kind === "surface") return 0;
    if (s.kind === "torus") return s.size[0] + s.size[1];
    if (s.kind === "solid") {
      let r = 0;
      for (let k = 0; k < s.mesh.v.length; k += 3) r = Math.max(r, Math.hypot(s.mesh.v[k], s.mesh.v[k + 1], s.mesh.v[k + 2]));
      return r;
    }
    return Math.max(s.size[0], s.size[1], s.size[2]);
  };
  // Every point a shape passes through, for the bounds of the scene.
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  const grow = (x, y, z, r) => {
    const p = [x, y, z];
    for (let k = 0; k < 3; ++k) {
      if (!isFinite(p[k])) continue;
      lo[k] = Math.min(lo[k], p[k] - r);
      hi[k] = Math.max(hi[k], p[k] + r);
    }
  };
  for (const s of S.shapes) {
    if (s.kind === "plane") continue;  // a ground plane's origin is not a place the motion goes
    const r = reach(s);
    for (let f = 0; f < frames; ++f) {
      grow(value(f, s.offset), value(f, s.offset + 1), value(f, s.offset + 2), r);
      if (s.kind === "segment") grow(value(f, s.offset + 3), value(f, s.offset + 4), value(f, s.offset + 5), 0);
    }
  }
  for (let k = 0; k < 3; ++k)
    if (!(lo[k] <= hi[k])) { lo[k] = -0.5; hi[k] = 0.5; }
  const extent = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 0.1);
  const centre = new THREE.Vector3((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2);
  // The size of the system itself: the largest span of its shapes at one time (a sled's blade and
  // arm, a bicycle's wheels and frame), and where their middle is at frame f (followed below).
  const points = (f) => {
    const out = [];
    for (const s of S.shapes) {
      if (s.kind === "frame" || s.kind === "plane") continue;
      const r = reach(s);
      for (const k of s.kind === "segment" ? [0, 3] : [0]) {
        const b = s.offset + k;
        out.push([value(f, b) - r, value(f, b + 1) - r, value(f, b + 2) - r], [value(f, b) + r, value(f, b + 1) + r, value(f, b + 2) + r]);
      }
    }
    return out;
  };
  const middle = (f) => {
    const a = [Infinity, Infinity, Infinity], z = [-Infinity, -Infinity, -Infinity];
    for (const p of points(f))
      for (let k = 0; k < 3; ++k)
        if (isFinite(p[k])) { a[k] = Math.min(a[k], p[k]); z[k] = Math.max(z[k], p[k]); }
    return { at: [(a[0] + z[0]) / 2, (a[1] + z[1]) / 2, (a[2] + z[2]) / 2], span: Math.max(z[0] - a[0], z[1] - a[1], z[2] - a[2]) };
  };
  let size = 0;
  for (let f = 0; f < frames; f += Math.max(1, Math.floor(frames / 50))) {
    const m = middle(f);
    if (isFinite(m.span)) size = Math.max(size, m.span);
  }
  if (!(size > 0)) size = extent;
  // Up is the side of the ground the bodies are on: +z, or -z for a model whose z points down
  // (gravity +z, as in the Whipple bicycle's convention).
  let heights = 0;
  for (let f = 0; f < frames; f += Math.max(1, Math.floor(frames / 50))) {
    const z = middle(f).at[2];
    if (isFinite(z)) heights += z;
  }
  const upward = S.ground && heights < 0 ? -1 : 1;
  // A system that travels far beyond its own size (a sled sliding 40 m, a bicycle riding 50 m) is
  // followed by default, seen at its own scale; points alone (a particle) have no shape to see, so
  // their whole motion is shown. "whole motion" in the menu shows it for any scene.
  const travels = extent > 12 * size && S.shapes.some((s) => s.kind !== "sphere");
  if (travels) follow.value = "-2";
  const near = Math.min(extent, 3 * size);  // the width of the view that follows

  const width = 640, height = 480;
  let renderer = null;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    el("div", { id: "nowebgl", text: "This browser offers no WebGL: the 3-D scene cannot be shown; the plots below still work." }, view);
  }
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  const camera = new THREE.PerspectiveCamera(40, width / height, near / 1000, extent * 100);
  if (renderer) {
    renderer.setPixelRatio(1);
    renderer.setSize(width, height);
    renderer.domElement.id = "canvas";
    view.appendChild(renderer.domElement);
  }
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  const sun = new THREE.DirectionalLight(0xffffff, 0.7);
  sun.position.set(1, -2, 3 * upward);
  scene.add(sun);

  // The ground (multibody) or the plane of a planar scene: a grid in z = 0, 1-2-5 spacing; a
  // contact's tilted plane: the same grid in the plane's axes (below, "plane").
  const niceStep = (span) => {
    const p = Math.pow(10, Math.floor(Math.log10(span)));
    const m = span / p;
    return (m < 2 ? 1 : m < 5 ? 2 : 5) * p;
  };
  const setPositions = (geometry, array) => {
    const attribute = new THREE.BufferAttribute(array, 3);
    if (geometry.setAttribute) geometry.setAttribute("position", attribute);
    else geometry.addAttribute("position", attribute);
  };
  // Two grids: one for the whole motion, a finer one for the view that follows (at most 600 lines
  // each way: a coarser step beyond). (cu, cv) is the middle of the motion in the grid's plane,
  // w its height along the plane's normal.
  const makeGrid = (view, cu, cv, w) => {
    const reach = extent * 0.75 + view;
    let step = niceStep(view / 8);
    if ((2 * reach) / step > 600) {  // the next 1-2-5 step at or above 2 reach / 600
      step = niceStep((2 * reach) / 600);
      if (step < (2 * reach) / 600) step = niceStep(step * 2.6);
    }
    // Lines x = const and y = const in the plane z = 0 (of the grid's axes), drawn directly (no
    // rotated GridHelper).
    const count = Math.ceil(reach / step);
    const cx = Math.round(cu / step) * step, cy = Math.round(cv / step) * step;
    const z = w, span = count * step;
    const minor = [], major = [];
    // Each line in pieces: a piece with an end behind the camera (the view that follows looks
    // along the ground) is not drawn by every WebGL implementation, so the pieces are short.
    const pieces = Math.min(2 * count, 100), piece = (2 * span) / pieces;
    for (let i = -count; i <= count; ++i) {  // the axes x = 0 and y = 0 darker
      const x = cx + i * step, y = cy + i * step;
      for (let k = 0; k < pieces; ++k) {
        const a = -span + k * piece, b = a + piece;
        (Math.abs(x) < step / 2 ? major : minor).push(x, cy + a, z, x, cy + b, z);
        (Math.abs(y) < step / 2 ? major : minor).push(cx + a, y, z, cx + b, y, z);
      }
    }
    const grid = new THREE.Group();
    for (const [lines, colour] of [[minor, 0xdddddd], [major, 0x999999]]) {
      const geometry = new THREE.BufferGeometry();
      setPositions(geometry, new Float32Array(lines));
      grid.add(new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color: colour })));
    }
    return grid;
  };
  // The grids whose visibility follows the view: [whole motion, follow] pairs (one object when the
  // two views have the same scale).
  const grids = [];
  const gridPair = (cu, cv, w, parent) => {
    const wide = makeGrid(extent, cu, cv, w);
    const close = near < extent / 3 ? makeGrid(near, cu, cv, w) : wide;
    parent.add(wide);
    if (close !== wide) parent.add(close);
    grids.push([wide, close]);
  };
  // The scene's contact planes (a tilted plane, a turntable) draw the grounds when there are any;
  // else the grid of z = 0 does (symbolic/visual.hpp: a level fixed plane is that grid).
  if (!S.shapes.some((s) => s.kind === "plane")) gridPair(centre.x, centre.y, S.planar ? -1e-3 * near : 0, scene);
  // A turntable: a translucent disk about its axis (the origin, along its normal) that holds every
  // place the shapes pass through, its grid, rim and twelve spokes, and a coloured sector on its
  // first axis, so that its turning shows.
  const turntable = (s) => {
    const b = s.offset;
    const n = [value(0, b + 5), value(0, b + 8), value(0, b + 11)];
    let rho = 0;
    for (let f = 0; f < frames; f += Math.max(1, Math.floor(frames / 200)))
      for (const p of points(f)) {
        const along = p[0] * n[0] + p[1] * n[1] + p[2] * n[2];
        const d = Math.hypot(p[0] - along * n[0], p[1] - along * n[1], p[2] - along * n[2]);
        if (isFinite(d)) rho = Math.max(rho, d);
      }
    rho = 1.15 * Math.max(rho, size, 1e-3);
    const table = new THREE.Group();
    const disk = new THREE.Mesh(new Circle(rho, 96), new THREE.MeshLambertMaterial({
      color: 0xa8c8a0, side: THREE.DoubleSide, transparent: true, opacity: 0.35, depthWrite: false }));
    table.add(disk);
    const sector = new THREE.Mesh(new Circle(rho, 8, -Math.PI / 24, Math.PI / 12), new THREE.MeshLambertMaterial({
      color: 0xff7f0e, side: THREE.DoubleSide, transparent: true, opacity: 0.45, depthWrite: false }));
    table.add(sector);
    const step = niceStep(rho / 4), count = Math.ceil(rho / step);
    const minor = [], major = [];
    for (let i = -count; i <= count; ++i) {  // chords x = const and y = const of the disk
      const x = i * step, half = Math.sqrt(Math.max(0, rho * rho - x * x));
      if (!(half > 0)) continue;
      minor.push(x, -half, 0, x, half, 0, -half, x, 0, half, x, 0);
    }
    for (let k = 0; k < 96; ++k) {  // the rim
      const a = (2 * Math.PI * k) / 96, c = (2 * Math.PI * (k + 1)) / 96;
      major.push(rho * Math.cos(a), rho * Math.sin(a), 0, rho * Math.cos(c), rho * Math.sin(c), 0);
    }
    for (let k = 0; k < 12; ++k) {  // the spokes
      const a = (2 * Math.PI * k) / 12;
      major.push(0, 0, 0, rho * Math.cos(a), rho * Math.sin(a), 0);
    }
    for (const [lines, colour] of [[minor, 0xbbbbbb], [major, 0x777777]]) {
      const geometry = new THREE.BufferGeometry();
      setPositions(geometry, new Float32Array(lines));
      table.add(new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color: colour })));
    }
    return table;
  };

  const colours = [0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf];
  const material = (i, opacity) => new THREE.MeshLambertMaterial({
    color: colours[i % colours.length], transparent: opacity < 1, opacity: opacity });
  const Sphere = THREE.SphereBufferGeometry || THREE.SphereGeometry;
  const Cylinder = THREE.CylinderBufferGeometry || THREE.CylinderGeometry;
  const Torus = THREE.TorusBufferGeometry || THREE.TorusGeometry;
  const Circle = THREE.CircleBufferGeometry || THREE.CircleGeometry;

  const trail = (points, colour) => {
    const geometry = new THREE.BufferGeometry();
    setPositions(geometry, points);
    geometry.setDrawRange(0, 1);
    const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: colour }));
    scene.add(line);
    return line;
  };
  const light = () => new THREE.MeshLambertMaterial({ color: 0xeeeeee });
  const shaped = new Set(S.shapes.filter((s) => s.body).map((s) => s.body));
  const objects = S.shapes.map((s, i) => {
    const o = { shape: s, object: null, trail: null };
    if (s.kind === "sphere") {
      o.object = new THREE.Mesh(new Sphere(s.size[0], 24, 16), material(i, 1));
      const points = new Float32Array(frames * 3);
      for (let f = 0; f < frames; ++f)
        for (let k = 0; k < 3; ++k) points[3 * f + k] = value(f, s.offset + k);
      o.trail = trail(points, 0x999999);
    } else if (s.kind === "segment") {
      o.object = new THREE.Mesh(new Cylinder(1, 1, 1, 8), material(i, 1));
    } else if (s.kind === "wheel") {
      // A tyre (torus) and two spokes about the axle, which is the frame's axis s.axis.
      const r = s.size[0];
      const group = new THREE.Group();
      const inner = new THREE.Group();
      inner.add(new THREE.Mesh(new Torus(r, r * 0.04, 8, 48), material(i, 1)));
      const disk = new THREE.Mesh(new Circle(r, 48), material(i, 0.25));
      disk.material.side = THREE.DoubleSide;
      inner.add(disk);
      for (const a of [0, Math.PI / 2]) {
        const spoke = new THREE.Mesh(new Cylinder(r * 0.02, r * 0.02, 2 * r, 6), material(i + 3, 1));
        spoke.rotation.z = a;
        inner.add(spoke);
      }
      // Torus and circle lie in their xy plane (axle z): turn z onto the frame's axle.
      if (s.axis === 0) inner.rotation.y = Math.PI / 2;
      if (s.axis === 1) inner.rotation.x = Math.PI / 2;
      group.add(inner);
      o.object = group;
      // The wheel's tilted plane, when it has one (a [[wheels]] entry with a `normal` drawn as its
      // contact's plane, of the same name): its normal is the wheel's up.
      const ground = S.shapes.find((p) => p.kind === "plane" && p.name === s.name);
      const points = new Float32Array(frames * 3);
      for (let f = 0; f < frames; ++f) {
        const c = [value(f, s.offset), value(f, s.offset + 1), value(f, s.offset + 2)];
        const a = [value(f, s.offset + 3 + s.axis), value(f, s.offset + 6 + s.axis), value(f, s.offset + 9 + s.axis)];
        // The contact point: the lowest point of the rim, c - r d with d the unit vector of the
        // vertical (up, +z or -z; the plane's normal n) within the wheel's plane.
        if (ground) {
          const n = [value(f, ground.offset + 5), value(f, ground.offset + 8), value(f, ground.offset + 11)];
          const na = n[0] * a[0] + n[1] * a[1] + n[2] * a[2];
          const d = [n[0] - na * a[0], n[1] - na * a[1], n[2] - na * a[2]];
          const norm = Math.hypot(d[0], d[1], d[2]) || 1;
          for (let k = 0; k < 3; ++k) points[3 * f + k] = c[k] - (r * d[k]) / norm;
          continue;
        }
        let d = [-a[2] * a[0], -a[2] * a[1], 1 - a[2] * a[2]];
        const norm = Math.hypot(d[0], d[1], d[2]) || 1;
        for (let k = 0; k < 3; ++k) points[3 * f + k] = c[k] - (upward * r * d[k]) / norm;
      }
      o.trail = trail(points, 0x444444);
    } else if (s.kind === "ellipsoid") {
      // The contact's ball or ellipsoid in eight octants of two colours, so that its turning shows.
      const group = new THREE.Group();
      const inner = new THREE.Group();
      for (let k = 0; k < 8; ++k) {
        const piece = new Sphere(1, 12, 8, (k % 4) * Math.PI / 2, Math.PI / 2, (k >> 2) * Math.PI / 2, Math.PI / 2);
        inner.add(new THREE.Mesh(piece, ((k + (k >> 2)) % 2) ? material(i, 1) : light()));
      }
      inner.scale.set(s.size[0], s.size[1], s.size[2]);
      group.add(inner);
      o.object = group;
    } else if (s.kind === "torus") {
      // The round tyre: the tube about the rim, in quarters of two colours; its axle the frame's s.axis.
      const group = new THREE.Group();
      const inner = new THREE.Group();
      for (let k = 0; k < 4; ++k) {
        const quarter = new THREE.Mesh(new Torus(s.size[0], s.size[1], 12, 16, Math.PI / 2), k % 2 ? material(i, 1) : light());
        quarter.rotation.z = (k * Math.PI) / 2;
        inner.add(quarter);
      }
      const disk = new THREE.Mesh(new Circle(s.size[0], 48), material(i, 0.25));
      disk.material.side = THREE.DoubleSide;
      inner.add(disk);
      if (s.axis === 0) inner.rotation.y = Math.PI / 2;
      if (s.axis === 1) inner.rotation.x = Math.PI / 2;
      group.add(inner);
      o.object = group;
    } else if (s.kind === "solid" || s.kind === "terrain" || s.kind === "surface") {
      // A mesh computed by nhdyn: a shape's zero set in its frame's axes (coloured by octant, so
      // that its turning shows), or a ground's in world axes.
      const geometry = new THREE.BufferGeometry();
      setPositions(geometry, new Float32Array(s.mesh.v));
      geometry.setIndex(s.mesh.i);
      geometry.computeVertexNormals();
      if (s.kind === "solid") {
        const c = new Float32Array(s.mesh.v.length);
        const a = new THREE.Color(colours[i % colours.length]), b = new THREE.Color(0xeeeeee);
        for (let k = 0; k < s.mesh.v.length; k += 3) {
          const odd = (s.mesh.v[k] < 0) !== (s.mesh.v[k + 1] < 0) !== (s.mesh.v[k + 2] < 0);
          (odd ? a : b).toArray(c, k);
        }
        const attribute = new THREE.BufferAttribute(c, 3);
        if (geometry.setAttribute) geometry.setAttribute("color", attribute); else geometry.addAttribute("color", attribute);
        const group = new THREE.Group();
        group.add(new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ vertexColors: THREE.VertexColors !== undefined ? THREE.VertexColors : true })));
        o.object = group;
      } else {
        const group = new THREE.Group();
        // A terrain coloured by height (low darker, high lighter), so that its relief shows.
        let zmin = Infinity, zmax = -Infinity;
        for (let k = 2; k < s.mesh.v.length; k += 3)
          if (s.mesh.v[k] !== null) { zmin = Math.min(zmin, s.mesh.v[k]); zmax = Math.max(zmax, s.mesh.v[k]); }
        const relief = s.kind === "terrain" && zmax > zmin;
        if (relief) {
          const c = new Float32Array(s.mesh.v.length);
          const low = new THREE.Color(0x6f9a68), high = new THREE.Color(0xe8f0d8), mix = new THREE.Color();
          for (let k = 0; k < s.mesh.v.length; k += 3)
            mix.copy(low).lerp(high, (s.mesh.v[k + 2] - zmin) / (zmax - zmin)).toArray(c, k);
          const attribute = new THREE.BufferAttribute(c, 3);
          if (geometry.setAttribute) geometry.setAttribute("color", attribute); else geometry.addAttribute("color", attribute);
        }
        const ground = new THREE.MeshLambertMaterial({ color: relief ? 0xffffff : 0xa8c8a0, side: THREE.DoubleSide, transparent: true,
                                                       opacity: s.kind === "surface" ? 0.45 : 0.8, depthWrite: false,
                                                       vertexColors: relief ? (THREE.VertexColors !== undefined ? THREE.VertexColors : true) : (THREE.NoColors !== undefined ? THREE.NoColors : false) });
        group.add(new THREE.Mesh(geometry, ground));
        // About a dozen lines each way along the mesh's grid (rows x columns of vertices).
        const rows = s.mesh.rows, columns = s.mesh.v.length / 3 / rows, lines = [];
        const every = (n) => Math.max(1, Math.round((n - 1) / 12));
        const vertex = (i, j) => { const k = 3 * (i * columns + j); return [s.mesh.v[k], s.mesh.v[k + 1], s.mesh.v[k + 2]]; };
        // A vertex where the ground is undefined is null: no line goes to it.
        const segment = (p, q) => { if (!p.includes(null) && !q.includes(null)) lines.push(...p, ...q); };
        for (let i = 0; i < rows; i += every(rows))
          for (let j = 0; j + 1 < columns; ++j) segment(vertex(i, j), vertex(i, j + 1));
        for (let j = 0; j < columns; j += every(columns))
          for (let i = 0; i + 1 < rows; ++i) segment(vertex(i, j), vertex(i + 1, j));
        const wire = new THREE.BufferGeometry();
        setPositions(wire, new Float32Array(lines));
        group.add(new THREE.LineSegments(wire, new THREE.LineBasicMaterial({ color: 0x6f8f68, transparent: true, opacity: 0.5 })));
        o.object = group;
      }
    } else if (s.kind === "plane") {
      // A contact's plane in its own axes (t1, t2, n: its frame, placed on each frame as the
      // others are): the grid about the middle of the motion in the plane, or a turntable.
      const group = new THREE.Group();
      if (s.turns) {
        group.add(turntable(s));
      } else {
        const b = s.offset;
        const t1 = [value(0, b + 3), value(0, b + 6), value(0, b + 9)], t2 = [value(0, b + 4), value(0, b + 7), value(0, b + 10)];
        gridPair(centre.x * t1[0] + centre.y * t1[1] + centre.z * t1[2], centre.x * t2[0] + centre.y * t2[1] + centre.z * t2[2],
                 0, group);
      }
      o.object = group;
    } else if (s.kind === "track") {
      // The contact point's path over the ground (the contact's NAME_X, NAME_Y, NAME_Z).
      const points = new Float32Array(frames * 3);
      for (let f = 0; f < frames; ++f)
        for (let k = 0; k < 3; ++k) points[3 * f + k] = value(f, s.offset + k);
      o.trail = trail(points, 0x444444);
      return o;
    } else if (s.kind === "body" && shaped.has(s.name)) {
      // A body drawn by its contact's shape: its ellipsoid of inertia would hide it.
      return o;
    } else if (s.kind === "body") {
      const group = new THREE.Group();
      const ball = new THREE.Mesh(new Sphere(1, 24, 16), material(i, 0.55));
      ball.scale.set(s.size[0], s.size[1], s.size[2]);
      group.add(ball);
      o.object = group;
    } else {
      o.object = new THREE.AxesHelper(near * 0.08);
    }
    if (s.kind !== "sphere" && s.kind !== "segment") o.object.matrixAutoUpdate = false;
    if (s.kind === "terrain" || s.kind === "surface") o.object.matrixAutoUpdate = true;  // fixed, in world axes
    scene.add(o.object);
    return o;
  });
  const up = new THREE.Vector3(0, 1, 0);
  // Segments are drawn 0.6 % of the view's width thick, and points no smaller than that, so that
  // they stay visible in the view of the whole motion as in the view that follows.
  let viewWidth = extent;
  const place = (f) => {
    const thin = 0.006 * viewWidth;
    for (const o of objects) {
      const s = o.shape, b = s.offset;
      if (!o.object || s.kind === "terrain" || s.kind === "surface") {
        if (o.trail) o.trail.geometry.setDrawRange(0, f + 1);
        continue;
      }
      if (s.kind === "sphere") {
        o.object.position.set(value(f, b), value(f, b + 1), value(f, b + 2));
        o.object.scale.setScalar(Math.max(1, thin / s.size[0]));
      } else if (s.kind === "segment") {
        const p = new THREE.Vector3(value(f, b), value(f, b + 1), value(f, b + 2));
        const q = new THREE.Vector3(value(f, b + 3), value(f, b + 4), value(f, b + 5));
        const d = q.clone().sub(p);
        const length = d.length();
        o.object.position.copy(p).add(q).multiplyScalar(0.5);
        o.object.scale.set(thin, Math.max(length, 1e-9), thin);
        if (length > 0) o.object.quaternion.setFromUnitVectors(up, d.multiplyScalar(1 / length));
      } else {
        const m = o.object.matrix;
        m.set(value(f, b + 3), value(f, b + 4), value(f, b + 5), value(f, b),
              value(f, b + 6), value(f, b + 7), value(f, b + 8), value(f, b + 1),
              value(f, b + 9), value(f, b + 10), value(f, b + 11), value(f, b + 2),
              0, 0, 0, 1);
        o.object.matrixWorldNeedsUpdate = true;
      }
      if (o.trail) o.trail.geometry.setDrawRange(0, f + 1);
    }
  };

  // Orbit camera: drag to turn about the target, wheel to zoom. z is up (y for a planar scene,
  // seen from +z).
  // The whole motion in view: the field of view is 40 degrees, tan(20 deg) = 0.36.
  const distance = (span) => (S.planar ? 1.6 : 2.0) * span;
  const orbit = S.planar ? { azimuth: -Math.PI / 2, elevation: Math.PI / 2 - 1e-3, distance: distance(extent) }
                         : { azimuth: -Math.PI / 3, elevation: 0.45, distance: distance(extent) };
  let zoom = 1;  // the wheel's zoom, kept when the view changes
  const target = centre.clone();
  const aim = () => {
    const ce = Math.cos(orbit.elevation);
    const offset = new THREE.Vector3(ce * Math.cos(orbit.azimuth), ce * Math.sin(orbit.azimuth), upward * Math.sin(orbit.elevation));
    // Looking (nearly) straight down, "up" on the screen is away from the camera's side.
    if (orbit.elevation > 1.55) camera.up.set(-Math.cos(orbit.azimuth), -Math.sin(orbit.azimuth), 0);
    else camera.up.set(0, 0, upward);
    camera.position.copy(target).addScaledVector(offset, orbit.distance);
    camera.lookAt(target);
  };
  if (renderer) {
    let dragging = null;
    const canvas = renderer.domElement;
    canvas.addEventListener("mousedown", (e) => { dragging = [e.clientX, e.clientY]; });
    window.addEventListener("mouseup", () => { dragging = null; });
    window.addEventListener("mousemove", (e) => {
      if (!dragging) return;
      orbit.azimuth -= (e.clientX - dragging[0]) * 0.01;
      orbit.elevation = Math.max(-1.5, Math.min(1.5707, orbit.elevation + (e.clientY - dragging[1]) * 0.01));
      dragging = [e.clientX, e.clientY];
      draw();
    });
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      zoom *= Math.exp(e.deltaY * 0.001);
      draw();
    }, { passive: false });
  }

  // ---- Plots -----------------------------------------------------------------------------------
  const plots = D.plots.map((p) => {
    const canvas = el("canvas", { class: "plot" }, right);
    const w = 560, h = 170;
    canvas.width = w;
    canvas.height = h;
    const g = canvas.getContext("2d");
    g.font = "11px sans-serif";
    // The legend after the title, in as many rows as it needs; the plot starts below it.
    const legendAt = [];
    let lx = 56 + g.measureText(p.title).width + 16, ly = 14;
    for (const series of p.series) {
      const wide = g.measureText(series.name).width;
      if (lx + wide > w - 6 && legendAt.length > 0) { lx = 56; ly += 13; }
      legendAt.push([lx, ly]);
      lx += wide + 12;
    }
    const x0 = 56, x1 = w - 10, y0 = ly + 8, y1 = h - 22;
    const t0 = T[0], t1 = T[frames - 1] > T[0] ? T[frames - 1] : T[0] + 1;
    const tx = (t) => x0 + ((t - t0) / (t1 - t0)) * (x1 - x0);
    // Values as drawn: log10 |v| on a log scale (zeros left out).
    const shown = p.series.map((s) => s.v.map((v) => (v === null ? NaN : p.log ? (v === 0 ? NaN : Math.log10(Math.abs(v))) : v)));
    let vmin = Infinity, vmax = -Infinity;
    for (const s of shown) for (const v of s) if (isFinite(v)) { vmin = Math.min(vmin, v); vmax = Math.max(vmax, v); }
    if (!(vmin <= vmax)) { vmin = 0; vmax = 1; }
    if (vmax - vmin < 1e-12 * Math.max(1, Math.abs(vmax))) { vmin -= 0.5; vmax += 0.5; }
    const ty = (v) => y1 - ((v - vmin) / (vmax - vmin)) * (y1 - y0);
    g.fillStyle = "#fff";
    g.fillRect(0, 0, w, h);
    g.font = "11px sans-serif";
    g.fillStyle = "#222";
    g.fillText(p.title, x0, 14);
    g.strokeStyle = "#888";
    g.strokeRect(x0, y0, x1 - x0, y1 - y0);
    // Ticks: 1-2-5 steps (decades on a log scale).
    const step = p.log ? Math.max(1, Math.round(niceStep((vmax - vmin) / 4))) : niceStep((vmax - vmin) / 4);
    g.fillStyle = "#555";
    for (let i = Math.ceil(vmin / step); i * step <= vmax + 1e-9 * step; ++i) {
      const v = i * step;  // a multiple of the step, printed without the float's accumulated error
      g.fillText(p.log ? "1e" + Math.round(v) : Number(v.toPrecision(6)).toString(), 2, ty(v) + 4);
      g.strokeStyle = "#eee";
      g.beginPath(); g.moveTo(x0, ty(v)); g.lineTo(x1, ty(v)); g.stroke();
    }
    const tstep = niceStep((t1 - t0) / 5);
    for (let i = Math.ceil(t0 / tstep); i * tstep <= t1 + 1e-9 * tstep; ++i)
      g.fillText(Number((i * tstep).toPrecision(6)).toString(), tx(i * tstep) - 8, h - 6);
    shown.forEach((s, k) => {
      g.strokeStyle = "#" + colours[k % colours.length].toString(16).padStart(6, "0");
      g.beginPath();
      let pen = false;
      for (let f = 0; f < frames; ++f) {
        if (!isFinite(s[f])) { pen = false; continue; }
        // Steps (a contact's mode): the value holds until the next frame, then jumps.
        if (pen && p.steps) g.lineTo(tx(T[f]), ty(s[f - 1]));
        if (pen) g.lineTo(tx(T[f]), ty(s[f])); else g.moveTo(tx(T[f]), ty(s[f]));
        pen = true;
      }
      g.stroke();
      g.fillStyle = g.strokeStyle;
      g.fillText(p.series[k].name, legendAt[k][0], legendAt[k][1]);
    });
    const background = g.getImageData(0, 0, w, h);
    return { cursor: (t) => {
      g.putImageData(background, 0, 0);
      g.strokeStyle = "#c00";
      g.beginPath(); g.moveTo(tx(t), y0); g.lineTo(tx(t), y1); g.stroke();
    } };
  });

  // ---- Equations -------------------------------------------------------------------------------
  const equations = el("div", { id: "equations" }, document.body);
  el("h2", { text: "Equations of motion" }, equations);
  // `nhdyn equations --format latex` writes one align* environment with \intertext between its
  // groups and %-comments above it, for a LaTeX document; KaTeX has no \intertext, so each group
  // becomes an aligned display and each \intertext a paragraph with its $...$ rendered inline.
  const renderEquations = (latex, box) => {
    const lines = latex.split("\n");
    for (const line of lines)
      if (line.startsWith("%") && !line.includes("usepackage")) el("p", { class: "comment", text: line.replace(/^%\s?/, "") }, box);
    let rest = lines.filter((line) => !line.startsWith("%")).join("\n")
      .replace("\\begin{align*}", "").replace("\\end{align*}", "");
    const options = { throwOnError: false, strict: "ignore" };
    while (true) {
      const i = rest.indexOf("\\intertext{");
      const rows = (i < 0 ? rest : rest.slice(0, i)).replace(/\\\\\s*$/, "");
      if (rows.trim())
        katex.render("\\begin{aligned}" + rows + "\\end{aligned}", el("div", {}, box), { ...options, displayMode: true });
      if (i < 0) break;
      let j = i + "\\intertext".length, depth = 0;
      for (; j < rest.length; ++j) {
        if (rest[j] === "{") ++depth;
        else if (rest[j] === "}" && --depth === 0) break;
      }
      const p = el("p", {}, box);
      rest.slice(i + "\\intertext{".length, j).split("$").forEach((part, k) => {
        if (k % 2 === 1) katex.render(part, el("span", {}, p), options);
        // Plain text: \texttt{...} loses its command, and LaTeX's escapes (roll\_x) their backslash.
        else p.appendChild(document.createTextNode(part.replace(/\\texttt\{((?:\\.|[^}\\])*)\}/g, "$1")
          .replace(/\\([_&%#{}$])/g, "$1")));
      });
      rest = rest.slice(j + 1);
    }
  };
  if (D.equations) {
    renderEquations(D.equations, el("div", {}, equations));
  } else {
    el("p", { text: D.equations_note }, equations);
  }

  // ---- Time ------------------------------------------------------------------------------------
  const draw = () => {
    const f = api.frame;
    const chosen = Number(follow.value);
    viewWidth = chosen === -1 ? extent : near;
    for (const [wide, close] of grids) {
      wide.visible = chosen === -1 || wide === close;
      close.visible = chosen !== -1 || wide === close;
    }
    orbit.distance = distance(viewWidth) * zoom;
    if (chosen >= 0) {
      const b = S.shapes[chosen].offset;
      target.set(value(f, b), value(f, b + 1), value(f, b + 2));
    } else if (chosen === -2) {
      target.fromArray(middle(f).at);
    } else {
      target.copy(centre);
    }
    place(f);
    aim();
    if (renderer) renderer.render(scene, camera);
    for (const p of plots) p.cursor(T[f]);
    timeLabel.textContent = "t = " + T[f].toFixed(3) + " s";
    slider.value = String(f);
  };
  // The frame shown at time t: the last one at or before t.
  const frameAt = (t) => {
    let a = 0, b = frames - 1;
    while (a < b) {
      const m = (a + b + 1) >> 1;
      if (T[m] <= t) a = m; else b = m - 1;
    }
    return a;
  };
  let playing = !/paused/.test(location.hash);
  let clock = T[0];
  play.textContent = playing ? "Pause" : "Play";
  play.addEventListener("click", () => {
    playing = !playing;
    play.textContent = playing ? "Pause" : "Play";
    last = null;
  });
  const show = (f) => {
    api.frame = Math.max(0, Math.min(frames - 1, f));
    clock = T[api.frame];
    draw();
  };
  slider.addEventListener("input", () => show(Number(slider.value)));
  follow.addEventListener("change", draw);
  api.setFrame = show;
  // Where shape i is on the page now, in CSS pixels (for tests: the screenshots differ there).
  api.screen = (i) => {
    const b = S.shapes[i].offset, f = api.frame;
    const p = new THREE.Vector3(value(f, b), value(f, b + 1), value(f, b + 2)).project(camera);
    const r = renderer ? renderer.domElement.getBoundingClientRect() : { left: 0, top: 0 };
    return [r.left + ((p.x + 1) / 2) * width, r.top + ((1 - p.y) / 2) * height];
  };
  let last = null;
  const tick = (now) => {
    if (playing && frames > 1) {
      if (last !== null) {
        clock += ((now - last) / 1000) * Number(speed.value);
        if (clock > T[frames - 1]) clock = T[0];
        const f = frameAt(clock);
        if (f !== api.frame) { api.frame = f; draw(); }
      }
      last = now;
    } else {
      last = null;
    }
    requestAnimationFrame(tick);
  };
  const start = /[#&]t=([0-9.eE+-]+)/.exec(location.hash);
  show(start ? frameAt(Number(start[1])) : 0);
  api.ready = true;
  requestAnimationFrame(tick);
})();
