// SPDX-License-Identifier: BSD-3-Clause
// The viewer page's panels, after viewer_template.js (in the same function): the charts of the
// requirements, the readout of magnitudes, the controls and the page's interface for tests.
// --- the readout of magnitudes: each arrow of a kind shown, its name and its magnitude now -------
// (each in its unit: forceUnit in viewer_template.js)
const magnitudesPanel = document.getElementById("magnitudes");
let magnitudesNow = [];
function drawMagnitudes() {
  magnitudesNow = [];
  for (const kind of Object.keys(arrows)) {
    for (const a of arrows[kind]) {
      if (!shown[kind] || a.value === null) continue;
      magnitudesNow.push({ name: a.name, kind: kind, torque: !!a.torque, value: a.value,
                           unit: a.unit, drawn: a.helper.visible });
    }
  }
  magnitudesPanel.textContent = "";
  magnitudesPanel.style.display = magnitudesNow.length ? "block" : "none";
  for (const m of magnitudesNow) {
    const line = document.createElement("div");
    line.className = "magnitude";
    const key = document.createElement("span");
    key.className = "key";
    key.style.background = ARROW[m.kind];
    line.appendChild(key);
    // (textContent: a name is only text)
    line.appendChild(document.createTextNode(m.name + ": " + m.value.toPrecision(4) + " " + m.unit));
    magnitudesPanel.appendChild(line);
  }
}

// --- the charts' legends: each series' colour and name, the axes and their units ------------------
// the unit of a requirement row where the page knows it: a row of a desired path is a position,
// a body's in its coordinates' unit (m), a point's in its coordinates' when it is exactly
// coordinates of one unit; else none (the page does not carry a requirement's own units)
function rowUnit(name) {
  for (const d of data.desired_paths || []) {
    if (!name.startsWith(d.requirement + ".")) continue;
    const coordinates = bodyIndex.has(d.of) ? [d.of + ".x", d.of + ".y"]
                      : pointIndex.has(d.of) ? data.points[pointIndex.get(d.of)].coordinates || [] : [];
    const units = coordinates.map((c) => (c ? data.units[c] : undefined));
    if (units.length && units.every((u) => u && u === units[0])) return units[0];
  }
  return "";
}
function axisLabel(text, units) {
  const known = units.every((u) => u && u === units[0]);
  return known ? text + " [" + units[0] + "]" : text + (units.length ? " (in each row\u2019s unit)" : "");
}
function fillLegend(id, rows, axes, note) {
  const legend = document.getElementById(id);
  legend.textContent = "";
  const line = (text) => {
    const div = document.createElement("div");
    div.textContent = text;
    legend.appendChild(div);
    return div;
  };
  rows.forEach((r, k) => {
    const div = line(r.name);
    div.className = "series";
    const key = document.createElement("span");
    key.className = "key";
    key.style.background = PALETTE[k % PALETTE.length];
    div.insertBefore(key, div.firstChild);
  });
  line(axes).className = "axes";
  if (note) line(note);
  legend.style.display = "block";
}

// --- the requirements' errors (controlled models) ----------------------------------------------------
const chart = document.getElementById("chart");
const errorAxis = axisLabel("error", data.requirements.map((r) => rowUnit(r.name)));
function drawChart() {
  if (!data.requirements.length) return;
  chart.style.display = "block";
  const g = chart.getContext("2d"), W = chart.width, H = chart.height;
  g.clearRect(0, 0, W, H);
  let lo = 0, hi = 0;
  for (const r of data.requirements) for (const v of r.error) { if (v < lo) lo = v; if (v > hi) hi = v; }
  if (hi - lo <= 0) hi = lo + 1;
  const t0 = data.t[0], t1 = data.t[N - 1] > t0 ? data.t[N - 1] : t0 + 1;
  const X = (t) => 30 + (W - 36) * (t - t0) / (t1 - t0), Y = (v) => H - 14 - (H - 28) * (v - lo) / (hi - lo);
  g.fillStyle = "#222"; g.font = "11px sans-serif";
  g.fillText("requirements' error (0 when met)", 30, 11);
  g.fillText("t [" + UNITS.time + "]", W - 30, H - 2);
  g.strokeStyle = "#bbb"; g.beginPath(); g.moveTo(30, Y(0)); g.lineTo(W - 6, Y(0)); g.stroke();
  data.requirements.forEach((r, k) => {
    g.strokeStyle = PALETTE[k % PALETTE.length]; g.beginPath();
    r.error.forEach((v, i) => { if (i) g.lineTo(X(data.t[i]), Y(v)); else g.moveTo(X(data.t[i]), Y(v)); });
    g.stroke();
  });
  g.strokeStyle = "#e6007e"; g.beginPath(); g.moveTo(X(data.t[frame]), 14); g.lineTo(X(data.t[frame]), H - 14); g.stroke();
  g.fillText(hi.toPrecision(2), 0, 22); g.fillText(lo.toPrecision(2), 0, H - 14);
}

// each requirement row's desired (dashed) and actual (solid) value over the run, where the
// requirement says what is desired (desired_<row>)
const pathsChart = document.getElementById("paths");
const tracked = data.requirements.filter((r) => r.desired);
const valueAxis = axisLabel("value", tracked.map((r) => rowUnit(r.name)));
if (data.requirements.length) fillLegend("chart-legend", data.requirements, "x: t [" + UNITS.time + "], y: " + errorAxis);
if (tracked.length) {
  fillLegend("paths-legend", tracked, "x: t [" + UNITS.time + "], y: " + valueAxis,
             "dashed: desired, solid: actual");
}
function drawPaths() {
  if (!tracked.length) return;
  pathsChart.style.display = "block";
  const g = pathsChart.getContext("2d"), W = pathsChart.width, H = pathsChart.height;
  g.clearRect(0, 0, W, H);
  let lo = Infinity, hi = -Infinity;
  for (const r of tracked) for (const v of r.desired.concat(r.actual)) {
    if (v === null) continue;
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  if (!(hi > lo)) { lo = (isFinite(lo) ? lo : 0) - 1; hi = lo + 2; }
  const t0 = data.t[0], t1 = data.t[N - 1] > t0 ? data.t[N - 1] : t0 + 1;
  const X = (t) => 30 + (W - 36) * (t - t0) / (t1 - t0), Y = (v) => H - 14 - (H - 28) * (v - lo) / (hi - lo);
  g.fillStyle = "#222"; g.font = "11px sans-serif";
  g.fillText("desired (dashed) and actual", 30, 11);
  g.fillText("t [" + UNITS.time + "]", W - 30, H - 2);
  const line = (values) => {
    g.beginPath();
    let up = false;
    values.forEach((v, i) => {
      if (v === null) { up = false; return; }
      if (up) g.lineTo(X(data.t[i]), Y(v)); else g.moveTo(X(data.t[i]), Y(v));
      up = true;
    });
    g.stroke();
  };
  tracked.forEach((r, k) => {
    g.strokeStyle = PALETTE[k % PALETTE.length];
    g.setLineDash([4, 3]); line(r.desired);
    g.setLineDash([]); line(r.actual);
  });
  g.strokeStyle = "#e6007e"; g.beginPath(); g.moveTo(X(data.t[frame]), 14); g.lineTo(X(data.t[frame]), H - 14); g.stroke();
  g.fillText(hi.toPrecision(2), 0, 22); g.fillText(lo.toPrecision(2), 0, H - 14);
}

// --- controls: play, pause, speed, slider, frame steps; orbit, pan and zoom (OrbitControls) ----------
const slider = document.getElementById("slider"), readout = document.getElementById("readout");
const playButton = document.getElementById("play"), speed = document.getElementById("speed");
slider.max = Math.max(0, N - 1);
let playing = false, simTime = 0, last = null, dirty = true;
function setPlaying(on) {
  playing = on && N > 1;
  playButton.innerHTML = playing ? "&#10074;&#10074;" : "&#9654;";
  last = null;
  simTime = data.t[frame];
}
playButton.onclick = () => setPlaying(!playing);
document.getElementById("back").onclick = () => { setPlaying(false); setFrame(frame - 1); };
document.getElementById("fwd").onclick = () => { setPlaying(false); setFrame(frame + 1); };
slider.oninput = () => { setFrame(+slider.value); simTime = data.t[frame]; };
for (const kind of ["ideal", "nonideal", "control", "contact", "trails", "desired", "triads", "axes"]) {
  const box = document.getElementById("show-" + kind);
  // (the contacts box shows and hides the friction at contacts too)
  box.onchange = () => {
    shown[kind] = box.checked;
    if (kind === "contact") shown.friction = box.checked;
    setFrame(frame);
  };
}
if (!arrows.nonideal.length)
  document.getElementById("show-nonideal").parentNode.style.display = "none";
if (!arrows.control.length) document.getElementById("label-control").style.display = "none";
if (!CONTACTS.length) document.getElementById("label-contact").style.display = "none";
if (!arrows.ideal.length) document.getElementById("show-ideal").parentNode.style.display = "none";
if (!trails.length) document.getElementById("show-trails").parentNode.style.display = "none";
if (!desired.length) document.getElementById("show-desired").parentNode.style.display = "none";
if (!bodyTriads.length) document.getElementById("label-triads").style.display = "none";
if (!jointAxes.some((a) => a)) document.getElementById("label-axes").style.display = "none";
document.addEventListener("keydown", (ev) => {
  if (ev.target.tagName === "SELECT") return;
  if (ev.key === " ") { setPlaying(!playing); ev.preventDefault(); }
  if (ev.key === "ArrowRight") { setPlaying(false); setFrame(frame + 1); }
  if (ev.key === "ArrowLeft") { setPlaying(false); setFrame(frame - 1); }
});
controls.addEventListener("change", () => { dirty = true; });
// a lost WebGL context (a busy GPU process) comes back empty: draw again when it is restored
renderer.domElement.addEventListener("webglcontextrestored", () => { dirty = true; });
window.addEventListener("resize", () => { fitCamera(); dirty = true; });

document.getElementById("name").textContent = data.model;
{
  const legend = document.getElementById("legend");
  for (const [kind, label] of [["ideal", "ideal"], ["nonideal", "non-ideal"], ["control", "control"],
                               ["contact", "contact force"], ["friction", "friction at contacts"]]) {
    if (!arrows[kind].length) continue;
    legend.insertAdjacentHTML("beforeend", '<span class="key" style="background:' + ARROW[kind] +
                              '"></span>' + label);
  }
  if (IMPACTS.length)
    legend.insertAdjacentHTML("beforeend", '<span class="key" style="background:' + IMPACT +
                              '"></span>impact');
  if (desired.length)
    legend.insertAdjacentHTML("beforeend", '<span class="key" style="background:repeating-linear-gradient(90deg,' +
                              DESIRED + ' 0 4px, transparent 4px 7px)"></span>desired path');
  // a torque is an arc around its axis (right-hand rule), in the colour of its kind
  if (Object.values(arrows).some((list) => list.some((a) => a.torque)))
    legend.insertAdjacentHTML("beforeend", '<span style="margin-left:10px">&#8634; torque: an arc about its axis (right-hand rule)</span>');
}

function tick(now) {
  if (playing) {
    if (last !== null) {
      simTime += (now - last) / 1000 * parseFloat(speed.value);
      if (simTime > data.t[N - 1]) simTime = data.t[0];
      // the last frame at or before simTime
      let lo = 0, hi = N - 1;
      while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (data.t[mid] <= simTime) lo = mid; else hi = mid - 1; }
      if (lo !== frame) setFrame(lo);
    }
    last = now;
  }
  if (dirty) {
    renderer.render(scene, camera);
    dirty = false;
    renderer.domElement.dispatchEvent(new Event("ukdyn-frame"));
  }
  requestAnimationFrame(tick);
}

{
  // the notes: what the page could not draw (textContent: a name is only text)
  const list = document.getElementById("notes");
  for (const text of notes) {
    const line = document.createElement("div");
    line.textContent = text;
    list.appendChild(line);
  }
}
fitCamera();
setFrame(0);
renderer.render(scene, camera);
requestAnimationFrame(tick);

// for tests and benchmarks (python/tests/test_viewer.py, bench/bench_viewer.py)
window.ukdyn = {
  data: data,
  frames: N,
  frame: () => frame,
  setFrame: (i) => { setPlaying(false); setFrame(i); renderer.render(scene, camera); dirty = false; },
  render: () => { renderer.render(scene, camera); dirty = false; },
  // the canvas as a PNG data URL, drawn now
  snapshot: () => { renderer.render(scene, camera); return renderer.domElement.toDataURL("image/png"); },
  show: (kind, on) => { const b = document.getElementById("show-" + kind); b.checked = on; b.onchange(); renderer.render(scene, camera); },
  // a robot link's frame at sample i by the page's forward kinematics: [x, y, z, qw, qx, qy, qz]
  robotFrame: (i, name) => {
    const k = ROBOT.findIndex((l) => l.name === name), f = robotAt[i] && robotAt[i][k];
    return f ? [f.pos.x, f.pos.y, f.pos.z, f.quat.w, f.quat.x, f.quat.y, f.quat.z] : null;
  },
  // a robot's URDF visuals as drawn in the frame shown: the link, the shape, the world position
  // of the visual's origin, the three.js geometries in it, whether it is the placeholder of a
  // mesh not drawn, its vertices and world bounds, and (a cylinder) the world direction of
  // three.js's cylinder axis
  robotVisuals: () => robotVisuals.map((r, k) => {
    r.holder.updateMatrixWorld(true);
    const geometries = [];
    let axis = null, vertices = 0;
    r.object.traverse((o) => {
      if (!o.isMesh) return;
      geometries.push(o.geometry.type);
      vertices += o.geometry.attributes.position.count;
      if (o.geometry.type === "CylinderBufferGeometry")
        axis = new T.Vector3(0, 1, 0).transformDirection(o.matrixWorld).toArray();
    });
    const bounds = new T.Box3().setFromObject(r.object);
    return { link: VISUALS[k].link_name, shape: VISUALS[k].shape, visible: r.holder.visible,
             bounds: [bounds.min.toArray(), bounds.max.toArray()],
             position: r.object.getWorldPosition(new T.Vector3()).toArray(), geometries: geometries,
             vertices: vertices, placeholder: r.placeholder, axis: axis };
  }),
  // a robot's contacts as drawn in the frame shown: the rod from the link's frame to the
  // contact's point (its ends, null without one) and the plane's patch (centre, normal, null)
  robotContacts: () => robotContactObjects.map((o, k) => {
    if (o.rod) o.rod.updateMatrixWorld(true);
    const rod = o.rod && o.rod.visible ? [-0.5, 0.5].map((s) => new T.Vector3(0, s, 0)
      .applyMatrix4(o.rod.matrixWorld).toArray()) : null;
    const plane = o.patch && o.patch.visible ? {
      centre: o.patch.position.toArray(),
      normal: new T.Vector3(0, 0, 1).applyQuaternion(o.patch.quaternion).toArray() } : null;
    return { name: ROBOT_CONTACTS[k].name, rod: rod, plane: plane };
  }),
  // the loops' polylines in the frame shown: link_a's frame, point a, point b, link_b's frame
  loops: () => loopObjects.map((o) => o.points.map((p) => p.toArray())),
  notes: () => notes.slice(),
  // the readout of the frame shown: each arrow of a kind shown, [{name, kind, torque, value, unit}]
  magnitudes: () => magnitudesNow.map((m) => Object.assign({}, m)),
  // what the triads and joint axes toggles draw: the body triads and joint axes visible now,
  // and each joint axis's world direction
  triadsShown: () => bodyTriads.filter((a) => a.visible).length,
  jointAxes: () => jointAxes.filter((a) => a).map((a) => ({
    visible: a.visible, position: a.position.toArray(),
    direction: new T.Vector3(0, 1, 0).applyQuaternion(a.quaternion).toArray() })),
  // the impact rings flashing in the frame shown (contacts)
  impactsShown: () => flashing,
  play: () => setPlaying(true),
  pause: () => setPlaying(false),
  camera: () => ({ position: camera.position.toArray(), target: controls.target.toArray(),
                   up: camera.up.toArray(), fov: camera.fov, aspect: camera.aspect,
                   width: renderer.domElement.clientWidth, height: renderer.domElement.clientHeight }),
  // the mean time of drawing `count` successive frames (ms), each waited for: reading a pixel
  // back makes the GPU process finish the frame
  frameTime: (count) => {
    const gl = renderer.getContext(), pixel = new Uint8Array(4);
    const start = performance.now();
    for (let k = 0; k < count; ++k) {
      setFrame((frame + 1) % N);
      renderer.render(scene, camera);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    }
    return (performance.now() - start) / count;
  },
  // plays for `ms` milliseconds and resolves to the frames drawn per second of wall time
  playbackRate: (ms) => new Promise((resolve) => {
    let drawn = 0;
    const counting = () => { drawn += 1; };
    renderer.domElement.addEventListener("ukdyn-frame", counting);
    setPlaying(true);
    setTimeout(() => { setPlaying(false); resolve(drawn / (ms / 1000)); }, ms);
  }),
  ready: true,
};
})();
