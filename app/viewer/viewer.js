// The page of a recorded rtcd run (rtcd view): the bodies and the ground
// posed at one step, the contacts the narrow phase found there as points
// coloured by depth with their pushes as arrows, the deepest pair
// highlighted, a timeline, the step's figures, and a click that names a body.
// Data: RTCD_VIEW from data/scene.js, .poses and .contacts from the other
// data scripts, all base64 (three.js r111, global THREE).
(function () {
  'use strict';
  const V = window.RTCD_VIEW;
  const started = performance.now();
  const $ = (id) => document.getElementById(id);

  function bytes(b64) {
    const text = atob(b64);
    const out = new Uint8Array(text.length);
    for (let i = 0; i < text.length; ++i) out[i] = text.charCodeAt(i);
    return out.buffer;
  }

  const steps = V.steps, bodies = V.body_look.length;
  const poses = new Float32Array(bytes(V.poses));
  const C = V.contacts && {
    offsets: new Uint32Array(bytes(V.contacts.offsets)),
    bodies: new Uint16Array(bytes(V.contacts.bodies)),
    points: new Uint16Array(bytes(V.contacts.points)),
    directions: new Int8Array(bytes(V.contacts.directions)),
    depths: new Float32Array(bytes(V.contacts.depths)),
    pushes: new Float32Array(bytes(V.contacts.pushes)),
  };
  const boxMin = new THREE.Vector3().fromArray(V.box[0]), boxMax = new THREE.Vector3().fromArray(V.box[1]);
  const extent = boxMax.clone().sub(boxMin);

  // The scene: z is up, as in the simulation.
  THREE.Object3D.DefaultUp.set(0, 0, 1);
  const host = $('view');
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(host.clientWidth, host.clientHeight);
  host.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xeef0f3);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a80, 0.65));

  // Framed like rtcd's snapshots: from the front right (-y, +x), above.
  const centre = boxMin.clone().add(boxMax).multiplyScalar(0.5);
  const radius = Math.max(extent.length() / 2, 1e-3);
  const fov = 40;
  const distance = (1.15 * radius) / Math.sin((fov / 2) * Math.PI / 180);
  const camera = new THREE.PerspectiveCamera(fov, host.clientWidth / host.clientHeight, distance / 1000, distance * 20);
  const eye = V.camera_eye ? new THREE.Vector3().fromArray(V.camera_eye)
                           : centre.clone().add(new THREE.Vector3(0.55, -1, 0.65).normalize().multiplyScalar(distance));
  const target = V.camera_target ? new THREE.Vector3().fromArray(V.camera_target) : centre;
  camera.position.copy(eye);
  const sun = new THREE.DirectionalLight(0xffffff, 0.55);
  sun.position.copy(eye.clone().sub(target).add(new THREE.Vector3(0, 0, distance)));
  scene.add(sun);
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.copy(target);
  controls.update();

  // Each look once; a mesh per body.
  const geometries = V.looks.map((look) => {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(bytes(look.positions)), 3));
    g.setIndex(new THREE.BufferAttribute(new Uint32Array(bytes(look.triangles)), 1));
    g.computeVertexNormals();
    return g;
  });
  const materials = V.looks.map((look) => new THREE.MeshLambertMaterial({
    color: new THREE.Color(look.colour[0], look.colour[1], look.colour[2]), side: THREE.DoubleSide }));
  const highlight = new THREE.MeshLambertMaterial({ color: 0xff2a2a, emissive: 0x551010, side: THREE.DoubleSide });
  const meshes = [];
  for (let b = 0; b < bodies; ++b) {
    const m = new THREE.Mesh(geometries[V.body_look[b]], materials[V.body_look[b]]);
    m.matrixAutoUpdate = false;
    m.userData.body = b;
    scene.add(m);
    meshes.push(m);
  }

  // The contact overlay: points and arrows, drawn over the bodies (a
  // contact lies inside both).
  let most = 0;
  if (C) for (let s = 0; s < steps; ++s) most = Math.max(most, C.offsets[s + 1] - C.offsets[s]);
  const pointGeometry = new THREE.BufferGeometry();
  pointGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * most), 3));
  pointGeometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * most), 3));
  const arrowGeometry = new THREE.BufferGeometry();
  arrowGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6 * most), 3));
  arrowGeometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(6 * most), 3));
  const points = new THREE.Points(pointGeometry, new THREE.PointsMaterial({
    size: 5, sizeAttenuation: false, vertexColors: THREE.VertexColors, depthTest: false }));
  const arrows = new THREE.LineSegments(arrowGeometry, new THREE.LineBasicMaterial({
    vertexColors: THREE.VertexColors, depthTest: false }));
  points.renderOrder = arrows.renderOrder = 1;
  points.frustumCulled = arrows.frustumCulled = false;
  scene.add(points, arrows);

  // Depths coloured from 0 (yellow) through red to purple at the run's
  // 99th percentile.
  let depthScale = 1e-3;
  if (C && C.depths.length) {
    const sorted = Float32Array.from(C.depths).sort();
    depthScale = Math.max(sorted[Math.floor(0.99 * (sorted.length - 1))], 1e-6);
  }
  function ramp(depth, out, at) {
    const t = Math.min(depth / depthScale, 1);
    if (t < 0.5) out.set([1, 1 - 2 * t, 0], at);
    else out.set([1 - (t - 0.5), 0, 2 * (t - 0.5)], at);
  }
  const mm = (metres) => (1e3 * metres).toFixed(metres < 1e-3 ? 3 : 2) + ' mm';
  $('range').textContent = '0 – ' + mm(depthScale) + ', ' + V.depth;
  $('title').textContent = V.name + ': ' + bodies + ' bodies, ' + steps + ' steps';
  if (!C) {
    $('contacts').checked = false;
    $('contacts').disabled = true;
    $('ramp').textContent = 'written without contacts (--no-contacts)';
  }

  function contactPoint(i, v) {
    return v.set(boxMin.x + (C.points[3 * i] / 65535) * extent.x, boxMin.y + (C.points[3 * i + 1] / 65535) * extent.y,
                 boxMin.z + (C.points[3 * i + 2] / 65535) * extent.z);
  }

  // The pair holding the step's deepest contact.
  function deepestPair(s) {
    let best = -1;
    if (C) for (let i = C.offsets[s]; i < C.offsets[s + 1]; ++i) if (best < 0 || C.depths[i] > C.depths[best]) best = i;
    return best < 0 ? null : { a: C.bodies[2 * best], b: C.bodies[2 * best + 1], depth: C.depths[best] };
  }

  let step = 0, firstFrame = null, picked = null;
  const fmt = (seconds) => (1e3 * seconds).toFixed(1);

  function show(s) {
    step = Math.max(0, Math.min(steps - 1, s | 0));
    const deep = deepestPair(step);
    for (let b = 0; b < bodies; ++b) {
      const p = poses.subarray((step * bodies + b) * 7, (step * bodies + b + 1) * 7);
      const m = meshes[b];
      m.visible = !Number.isNaN(p[0]);
      if (!m.visible) continue;
      m.position.set(p[0], p[1], p[2]);
      m.quaternion.set(p[3], p[4], p[5], p[6]);
      m.updateMatrix();
      m.material = deep && (b === deep.a || b === deep.b) && V.body_look[b] < V.looks.length - 1
        ? highlight : materials[V.body_look[b]];
    }
    let n = 0;
    if (C && $('contacts').checked) {
      const pos = pointGeometry.attributes.position.array, col = pointGeometry.attributes.color.array;
      const apos = arrowGeometry.attributes.position.array, acol = arrowGeometry.attributes.color.array;
      const scale = Number($('arrows').value) || 0;
      const v = new THREE.Vector3();
      for (let i = C.offsets[step]; i < C.offsets[step + 1]; ++i, ++n) {
        contactPoint(i, v);
        v.toArray(pos, 3 * n);
        v.toArray(apos, 6 * n);
        const l = scale * C.pushes[i] / 127;
        apos.set([v.x + l * C.directions[3 * i], v.y + l * C.directions[3 * i + 1], v.z + l * C.directions[3 * i + 2]],
                 6 * n + 3);
        ramp(C.depths[i], col, 3 * n);
        acol.set(col.subarray(3 * n, 3 * n + 3), 6 * n);
        acol.set(col.subarray(3 * n, 3 * n + 3), 6 * n + 3);
      }
      for (const g of [pointGeometry, arrowGeometry]) {
        g.attributes.position.needsUpdate = true;
        g.attributes.color.needsUpdate = true;
      }
    }
    pointGeometry.setDrawRange(0, n);
    arrowGeometry.setDrawRange(0, 2 * n);
    const F = V.figures;
    $('timeline').value = step;
    $('at').textContent = 'step ' + step + ' / ' + (steps - 1) + ', t = ' + F.time[step].toFixed(3) + ' s';
    $('figures').textContent = 'pairs ' + F.pairs[step] + ' · contacts ' + F.contacts[step] +
      (C ? ' (replayed ' + (C.offsets[step + 1] - C.offsets[step]) + ')' : '') +
      ' · deepest ' + (deep ? mm(deep.depth) : '–') + ' · ms: broad ' + fmt(F.broad[step]) + ', narrow ' +
      fmt(F.narrow[step]) + ', solver ' + fmt(F.solver[step]) + ', effects ' + fmt(F.effects[step]) + ', step ' +
      fmt(F.total[step]);
    $('deepest').textContent = deep ? 'deepest pair: ' + V.labels[deep.a] + ' – ' + V.labels[deep.b] + ', ' + mm(deep.depth)
                                    : 'no contacts this step';
    if (picked !== null) describe(picked);
    draw();
  }

  function draw() {
    renderer.render(scene, camera);
    if (firstFrame === null) firstFrame = performance.now() - started;
    probe();
  }

  // What the tests read: the step, where its bodies' centres are on the
  // screen, what is drawn.
  function probe() {
    const w = renderer.domElement.width, h = renderer.domElement.height;
    const box = [Infinity, Infinity, -Infinity, -Infinity], v = new THREE.Vector3();
    let drawn = 0;
    for (let b = 0; b < bodies; ++b) {
      if (!meshes[b].visible || V.body_look[b] === V.looks.length - 1) continue;
      v.setFromMatrixPosition(meshes[b].matrix).project(camera);
      const x = (v.x + 1) / 2 * w, y = (1 - v.y) / 2 * h;
      box[0] = Math.min(box[0], x); box[1] = Math.min(box[1], y);
      box[2] = Math.max(box[2], x); box[3] = Math.max(box[3], y);
      ++drawn;
    }
    const legend = $('legend').getBoundingClientRect();
    $('probe').textContent = JSON.stringify({
      step, first_frame_ms: firstFrame, bodies_drawn: drawn, canvas: [w, h], centres_box: box,
      legend: [legend.left, legend.top, legend.right, legend.bottom],
      contacts_drawn: pointGeometry.drawRange.count, picked: picked === null ? null : V.labels[picked] });
  }

  function describe(b) {
    let n = 0, deepest = 0;
    const touching = new Set();
    if (C) for (let i = C.offsets[step]; i < C.offsets[step + 1]; ++i) {
      const s = C.bodies[2 * i], t = C.bodies[2 * i + 1];
      if (s !== b && t !== b) continue;
      ++n;
      deepest = Math.max(deepest, C.depths[i]);
      touching.add(s === b ? t : s);
    }
    const look = V.looks[V.body_look[b]];
    const names = [...touching].slice(0, 8).map((o) => V.labels[o]).join(', ');
    $('picked').style.display = 'block';
    $('picked').innerHTML = '';
    const lines = ['body ' + b + ': ' + V.labels[b], 'shape: ' + look.label + ' (' + look.shape + ')',
                   'appears at step ' + V.first_step[b],
                   C ? 'this step: ' + n + ' contacts' + (n ? ', deepest ' + mm(deepest) : '') : 'contacts not written',
                   touching.size ? 'touching: ' + names + (touching.size > 8 ? ', …' : '') : ''];
    for (const line of lines) if (line) $('picked').appendChild(document.createElement('div')).textContent = line;
  }

  // A click (not the end of a drag) names the body under it.
  const raycaster = new THREE.Raycaster();
  let down = null;
  renderer.domElement.addEventListener('pointerdown', (e) => { down = [e.clientX, e.clientY]; });
  renderer.domElement.addEventListener('click', (e) => {
    if (down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
    const r = renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    const hit = raycaster.intersectObjects(meshes.filter((m) => m.visible))[0];
    picked = hit ? hit.object.userData.body : null;
    if (picked === null) $('picked').style.display = 'none';
    else describe(picked);
    probe();
  });

  // The timeline.
  let playing = false, last = 0, carry = 0;
  $('timeline').max = steps - 1;
  $('timeline').addEventListener('input', () => { pause(); show(Number($('timeline').value)); note(); });
  $('back').addEventListener('click', () => { pause(); show(step - 1); note(); });
  $('forward').addEventListener('click', () => { pause(); show(step + 1); note(); });
  $('play').addEventListener('click', () => (playing ? pause() : play()));
  $('contacts').addEventListener('change', () => show(step));
  $('arrows').addEventListener('change', () => show(step));
  controls.addEventListener('change', draw);
  function note() { history.replaceState(null, '', '#step=' + step + ($('contacts').checked ? '' : '&contacts=0')); }
  function pause() { playing = false; $('play').textContent = 'play'; }
  function play() {
    if (step >= steps - 1) show(0);
    playing = true;
    $('play').textContent = 'pause';
    last = performance.now();
    carry = 0;
    requestAnimationFrame(tick);
  }
  function tick(now) {
    if (!playing) return;
    carry += ((now - last) / 1e3) * Number($('speed').value) / V.time_step;
    last = now;
    const advance = Math.floor(carry);
    carry -= advance;
    if (advance > 0) show(step + advance);
    if (step >= steps - 1) { pause(); note(); return; }
    requestAnimationFrame(tick);
  }
  window.addEventListener('resize', () => {
    renderer.setSize(host.clientWidth, host.clientHeight);
    camera.aspect = host.clientWidth / host.clientHeight;
    camera.updateProjectionMatrix();
    draw();
  });

  // The address: #step=N&contacts=0|1&click=X,Y.
  function fromAddress() {
    const args = new URLSearchParams(location.hash.slice(1));
    if (args.has('contacts') && C) $('contacts').checked = args.get('contacts') !== '0';
    show(args.has('step') ? Number(args.get('step')) : 0);
    if (args.has('click')) {
      const [x, y] = args.get('click').split(',').map(Number);
      const r = renderer.domElement.getBoundingClientRect();
      down = null;
      renderer.domElement.dispatchEvent(new MouseEvent('click', { clientX: r.left + x, clientY: r.top + y, bubbles: true }));
    }
  }
  window.addEventListener('hashchange', fromAddress);
  fromAddress();
})();
