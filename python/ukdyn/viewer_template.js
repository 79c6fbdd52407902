// SPDX-License-Identifier: BSD-3-Clause
// The ukdyn viewer page's script (docs/viewer.md), then viewer_panels.js: both put, in that
// order, in place of /*UKDYN_SCRIPT*/ in viewer_template.html (python/ukdyn/viewer.py,
// app/embed_viewer.cmake), inside one function: the scene, its objects and setFrame here.
"use strict";
(function () {
const data = JSON.parse(document.getElementById("ukdyn-data").textContent);
const T = THREE;
const N = data.t.length;
// body colours (matplotlib's tab10 without red, pink and grey, kept for the arrows and the ground)
const PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#bcbd22", "#17becf",
                 "#393b79", "#637939", "#8c6d31"];
const ARROW = { ideal: "#e6007e", nonideal: "#ff2a00", control: "#00a651", contact: "#0050ff",
                friction: "#9b30ff" };
// the unilateral contacts (visual: contacts:) and the flash of their impacts
const CONTACTS = data.contacts || [], IMPACTS = data.impacts || [], IMPACT = "#ffb000";

// --- the pose of each body at each frame ---------------------------------------------------
function bodyPose(b, i, pos, quat) {
  const q = b.q;
  if (b.kind === "planar") {
    pos.set(q[0][i], q[1][i], 0);
    quat.setFromAxisAngle(new T.Vector3(0, 0, 1), q[2][i]);
  } else if (b.kind === "rigid") {
    pos.set(q[0][i], q[1][i], q[2][i]);
    quat.set(q[4][i], q[5][i], q[6][i], q[3][i]).normalize();
  } else {
    pos.set(q[0][i], q[1][i], q[2][i]);
    quat.set(0, 0, 0, 1);
  }
}
// a point's or frame's position at sample i; null while it is not finite (stored as null: the
// page hides it then, rather than draw it at 0)
function pointAt(p, i, out) {
  if (p.q.some((c) => c[i] === null || c[i] === undefined)) return null;
  return out.set(p.q[0][i], p.q[1][i], p.q.length > 2 ? p.q[2][i] : 0);
}
// a frame of visual: (its origin as a point's; its orientation by angle about z or quaternion)
function frameRotation(f, i, quat) {
  if (f.r.length === 1) return quat.setFromAxisAngle(new T.Vector3(0, 0, 1), f.r[0][i]);
  return quat.set(f.r[1][i], f.r[2][i], f.r[3][i], f.r[0][i]).normalize();
}
// where a named point, frame or body is at sample i
function positionOf(name, i, out) {
  if (pointIndex.has(name)) return pointAt(data.points[pointIndex.get(name)], i, out);
  if (frameIndex.has(name)) return pointAt(data.frames[frameIndex.get(name)], i, out);
  bodyPose(data.bodies[bodyIndex.get(name)], i, out, new T.Quaternion());
  return out;
}
// name -> index; Maps, so that a name such as __proto__ or constructor is only a name
const pointIndex = new Map(), frameIndex = new Map(), bodyIndex = new Map();
data.points.forEach((p, k) => { pointIndex.set(p.name, k); });
data.frames.forEach((f, k) => { frameIndex.set(f.name, k); });
data.bodies.forEach((b, k) => { bodyIndex.set(b.name, k); });

// --- a robot (robot: or a .urdf): each link's frame by forward kinematics --------------------------
// link i's frame = its parent's frame · the joint's origin (p, r) · the joint's motion by its
// coordinates (a rotation about the axis, a translation along it, or a floating base's
// position and quaternion); links are listed parents first
const ROBOT = data.robot ? data.robot.links : [];
function robotFrames(i) {
  const frames = [];
  for (const l of ROBOT) {
    const pos = new T.Vector3(...l.p), quat = new T.Quaternion(l.r[1], l.r[2], l.r[3], l.r[0]);
    const q = l.q.map((c) => c[i]);
    if (q.some((v) => v === null || v === undefined)) return null;
    const axis = new T.Vector3(...l.axis).normalize();
    if (l.kind === "revolute" || l.kind === "continuous") {
      quat.multiply(new T.Quaternion().setFromAxisAngle(axis, q[0]));
    } else if (l.kind === "prismatic") {
      pos.add(axis.clone().multiplyScalar(q[0]).applyQuaternion(quat));
    } else if (l.kind === "floating") {
      pos.add(new T.Vector3(q[0], q[1], q[2]).applyQuaternion(quat));
      quat.multiply(new T.Quaternion(q[4], q[5], q[6], q[3]).normalize());
    }
    if (l.parent >= 0) {
      const up = frames[l.parent];
      pos.applyQuaternion(up.quat).add(up.pos);
      quat.premultiply(up.quat);
    }
    frames.push({ pos: pos, quat: quat });
  }
  return frames;
}
const robotAt = ROBOT.length ? Array.from({ length: N }, (_, i) => robotFrames(i)) : [];

// --- a robot's URDF visuals: box, cylinder, sphere, meshes (their files embedded in the data) --
// each is drawn in its link's frame (link -1: the world) at its origin (p, r). A mesh the page
// cannot draw (its file not found beside the URDF, a format without a loader, a file the loader
// refuses) is a grey wire box at its origin, and the notes under the scene say why
const VISUALS = data.robot && data.robot.visuals ? data.robot.visuals : [];
const LOOPS = data.robot && data.robot.loops ? data.robot.loops : [];
const MESHES = data.robot && data.robot.meshes ? data.robot.meshes : [], parsed = new Map();
const notes = [], ROBOT_SOLID = "#a8b8cc";
// three.js's own loaders (Debian's libjs-three, examples/js/loaders), put in the page by its
// writer for the formats the data holds; COLLADA's turn of a Z_UP file to three.js's y up is
// undone: URDF meshes are in their link's frame, and the scene's z is up
const MESH_LOADERS = {
  stl: { loader: "STLLoader", parse: (bytes) => new T.Mesh(new T.STLLoader().parse(bytes.buffer)) },
  obj: { loader: "OBJLoader", parse: (bytes) => new T.OBJLoader().parse(new TextDecoder().decode(bytes)) },
  dae: { loader: "ColladaLoader", parse: (bytes) => {
    const dae = new T.ColladaLoader().parse(new TextDecoder().decode(bytes), "").scene;
    dae.quaternion.set(0, 0, 0, 1);
    return dae;
  } },
};
function base64Bytes(text) {
  const raw = atob(text), bytes = new Uint8Array(raw.length);
  for (let k = 0; k < raw.length; ++k) bytes[k] = raw.charCodeAt(k);
  return bytes;
}
function visualObject(v) {
  // the URDF's colour and alpha, else a light steel (none of the colours of forces and paths)
  const material = new T.MeshLambertMaterial({ color: v.color || ROBOT_SOLID });
  if (typeof v.opacity === "number" && v.opacity < 1) {
    material.transparent = true;
    material.opacity = v.opacity;
  }
  let object = null, problem = null;
  if (v.shape === "box") {
    object = new T.Mesh(new T.BoxBufferGeometry(v.size[0], v.size[1], v.size[2]), material);
  } else if (v.shape === "sphere") {
    object = new T.Mesh(new T.SphereBufferGeometry(v.radius, 24, 16), material);
  } else if (v.shape === "cylinder") {
    // URDF's cylinder is along the visual's z, three.js's along y: turned by 90° about x
    const c = new T.Mesh(new T.CylinderBufferGeometry(v.radius, v.radius, v.length, 24), material);
    c.rotation.x = Math.PI / 2;
    object = new T.Group();
    object.add(c);
  } else if (typeof v.file !== "number" || !MESHES[v.file]) {
    problem = v.problem || "its file is not in the page";
  } else if (!MESH_LOADERS[v.format] || typeof T[MESH_LOADERS[v.format].loader] !== "function") {
    problem = "this page has no loader for its format";
  } else {
    try {
      // each file parsed once; a visual that shows it again gets a copy sharing its geometry
      if (!parsed.has(v.file)) parsed.set(v.file, MESH_LOADERS[v.format].parse(base64Bytes(MESHES[v.file])));
      const inner = parsed.get(v.file).clone();
      // a COLLADA file keeps its own materials unless the URDF gives a colour
      inner.traverse((o) => { if (o.isMesh && (v.color || v.format !== "dae")) o.material = material; });
      inner.scale.multiply(new T.Vector3(v.scale[0], v.scale[1], v.scale[2]));  // (COLLADA's unit kept)
      object = new T.Group();
      object.add(inner);
    } catch (e) {
      problem = "its file could not be read (" + String(e && e.message) + ")";
    }
  }
  if (problem !== null) {
    notes.push("mesh " + JSON.stringify(String(v.mesh)) + " of link " + JSON.stringify(String(v.link_name)) +
               " is not drawn: " + problem + "; a grey wire box marks its origin");
    object = new T.Mesh(new T.BoxBufferGeometry(1, 1, 1),
                        new T.MeshBasicMaterial({ color: 0x808080, wireframe: true }));
  }
  object.position.set(v.p[0], v.p[1], v.p[2]);
  object.quaternion.set(v.r[1], v.r[2], v.r[3], v.r[0]).normalize();
  // the holder follows the link's frame; its reach: the farthest corner of its bounds
  const holder = new T.Group();
  holder.add(object);
  let reach = 0;
  if (problem === null) {
    holder.updateMatrixWorld(true);
    const bounds = new T.Box3().setFromObject(holder);
    if (!bounds.isEmpty()) {
      for (const c of [bounds.min, bounds.max]) reach = Math.max(reach, c.length());
    }
  }
  return { holder: holder, object: object, placeholder: problem !== null, reach: reach };
}
const robotVisuals = VISUALS.map(visualObject);

// --- the extent of the motion: the camera and the default sizes follow it ---------------------
const box = new T.Box3(), centres = new T.Box3();
{
  const pos = new T.Vector3(), quat = new T.Quaternion();
  for (let i = 0; i < N; ++i) {
    for (const b of data.bodies) { bodyPose(b, i, pos, quat); box.expandByPoint(pos); }
    for (const p of data.points) if (pointAt(p, i, pos)) box.expandByPoint(pos);
    for (const f of data.frames) if (pointAt(f, i, pos)) box.expandByPoint(pos);
    for (const f of (robotAt[i] || [])) box.expandByPoint(f.pos);
    // (a contact's point: a robot's tip beyond its last link's frame)
    for (const c of CONTACTS) if (pointAt(c, i, pos)) box.expandByPoint(pos);
  }
  if (box.isEmpty()) box.set(new T.Vector3(-1, -1, 0), new T.Vector3(1, 1, 0));
}
// solids: the declared ones, else the equivalent box of the inertia
function defaultSolids(b, size) {
  const m = b.mass || 1, J = b.inertia || [0, 0, 0];
  if (b.kind === "particle") return [{ shape: "sphere", radius: 0.03 * size, offset: [0, 0, 0] }];
  let e;
  if (b.kind === "planar") {
    // a bar along the body's x axis, as thick as a tenth of its length: I = m (a² + b²) / 12
    const a = Math.sqrt(12 * J[2] / (1.01 * m));
    e = [a, a / 10, a / 10];
  } else {
    // the box whose principal inertias are J: a² = 6 (J2 + J3 − J1) / m, …
    e = [Math.sqrt(Math.max(0, 6 * (J[1] + J[2] - J[0]) / m)),
         Math.sqrt(Math.max(0, 6 * (J[0] + J[2] - J[1]) / m)),
         Math.sqrt(Math.max(0, 6 * (J[0] + J[1] - J[2]) / m))];
  }
  const big = Math.max(e[0], e[1], e[2], 1e-3 * size);
  return [{ shape: "box", size: e.map((v) => Math.max(v, 0.04 * big)), offset: [0, 0, 0] }];
}
function solidExtent(s) {
  if (s.shape === "box") return Math.max(...s.size) / 2;
  return s.radius + (s.length || 0) / 2;
}
for (const b of data.bodies) b.solids = b.visual && b.visual.length ? b.visual : null;
{
  // the bodies' reach around their centres widens the box
  let reach = 0;
  const size0 = Math.max(box.getSize(new T.Vector3()).length(), 1e-3);
  for (const b of data.bodies) {
    const solids = b.solids || defaultSolids(b, size0);
    for (const s of solids) reach = Math.max(reach, solidExtent(s) + new T.Vector3(...s.offset).length());
  }
  for (const p of data.points) reach = Math.max(reach, p.radius || 0.025 * size0);
  for (const r of robotVisuals) reach = Math.max(reach, r.reach);
  for (const f of data.frames) reach = Math.max(reach, f.size || 0.08 * size0);
  centres.copy(box);
  box.expandByScalar(reach);
}
const center = box.getCenter(new T.Vector3());
const extent = box.getSize(new T.Vector3());
const size = Math.max(extent.length(), 1e-3);

// --- renderer, scene, camera, lights ------------------------------------------------------------
const view = document.getElementById("view");
const renderer = new T.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.setClearColor(0xffffff, 1);
view.appendChild(renderer.domElement);
const scene = new T.Scene();
const camera = new T.PerspectiveCamera(35, 1, size * 1e-3, size * 100);
scene.add(camera);
scene.add(new T.AmbientLight(0xffffff, 0.55));
const light = new T.DirectionalLight(0xffffff, 0.5);
light.position.set(0, 0, 1);  // from the camera: faces turned to the viewer are evenly lit
camera.add(light);
const controls = new T.OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;
controls.screenSpacePanning = true;

function fitCamera() {
  const w = view.clientWidth || 640, h = view.clientHeight || 480;
  renderer.setSize(w, h);
  camera.aspect = w / h;
  const tan = Math.tan(camera.fov * Math.PI / 360);
  if (data.planar) {
    // facing the (x, y) plane, y up
    const half = Math.max(extent.y / 2, extent.x / 2 / camera.aspect) * 1.15;
    camera.up.set(0, 1, 0);
    camera.position.set(center.x, center.y, center.z + half / tan + extent.z / 2);
  } else {
    // z up, seen from the front right and above
    const dir = new T.Vector3(1.2, -2.0, 1.0).normalize();
    camera.up.set(0, 0, 1);
    camera.position.copy(center).addScaledVector(dir, size * 0.45 / tan);
  }
  controls.target.copy(center);
  camera.updateProjectionMatrix();
  controls.update();
}

// --- the ground -----------------------------------------------------------------------------------
{
  const span = Math.pow(10, Math.ceil(Math.log10(size * 2)));
  const grid = new T.GridHelper(span, 20, 0xc8c8c8, 0xe4e4e4);
  grid.rotation.x = Math.PI / 2;  // into the (x, y) plane
  // spatial: the plane z = 0 when everything moves above it (z is up), else below the motion
  const z = data.planar ? box.min.z - 0.05 * size : (centres.min.z >= 0 ? 0 : box.min.z);
  grid.position.set(center.x, center.y, z);
  scene.add(grid);
}

// --- bodies -------------------------------------------------------------------------------------
function solidMesh(s, colour) {
  const material = new T.MeshLambertMaterial({ color: colour });
  let geometry;
  const group = new T.Group();
  if (s.shape === "box") {
    geometry = new T.BoxBufferGeometry(s.size[0], s.size[1], s.size[2]);
  } else if (s.shape === "sphere") {
    geometry = new T.SphereBufferGeometry(s.radius, 24, 16);
  } else {
    geometry = new T.CylinderBufferGeometry(s.radius, s.radius, s.length, 24);
    if (s.shape === "capsule") {
      for (const end of [-1, 1]) {
        const cap = new T.Mesh(new T.SphereBufferGeometry(s.radius, 24, 12), material);
        cap.position.y = end * s.length / 2;
        group.add(cap);
      }
    }
  }
  group.add(new T.Mesh(geometry, material));
  // the cylinder's axis is y: turned onto the body axis asked for
  if (s.axis === "x") group.rotation.z = -Math.PI / 2;
  if (s.axis === "z") group.rotation.x = Math.PI / 2;
  group.position.set(s.offset[0], s.offset[1], s.offset[2] || 0);
  return group;
}
// each body's frame triad (x red, y green, z blue, at its centre), shown on request (triads)
function triad(len) {
  const group = new T.Group();
  for (const [x, y, z, colour] of [[1, 0, 0, 0xcc0000], [0, 1, 0, 0x00aa00], [0, 0, 1, 0x0000cc]])
    group.add(new T.ArrowHelper(new T.Vector3(x, y, z), new T.Vector3(), len, colour, 0.2 * len, 0.1 * len));
  return group;
}
const bodyTriads = [];
const bodyObjects = data.bodies.map((b, k) => {
  const group = new T.Group();
  const colour = PALETTE[k % PALETTE.length];
  const solids = b.solids || defaultSolids(b, size);
  for (const s of solids) group.add(solidMesh(s, s.color || colour));
  // the triad reaches out of the body: 1.3 times its solids' reach, at least 0.06 of the scene
  let reach = 0;
  for (const s of solids) reach = Math.max(reach, solidExtent(s) + new T.Vector3(...s.offset).length());
  const axes = triad(Math.max(1.3 * reach, 0.06 * size));
  axes.visible = false;
  group.add(axes);
  bodyTriads.push(axes);
  scene.add(group);
  return group;
});

// --- points and links (models in coordinates) -----------------------------------------------------
const pointObjects = data.points.map((p, k) => {
  const r = p.radius || 0.025 * size;
  const mesh = new T.Mesh(new T.SphereBufferGeometry(r, 24, 16),
                          new T.MeshLambertMaterial({ color: p.color || PALETTE[k % PALETTE.length] }));
  scene.add(mesh);
  return mesh;
});
const linkObjects = data.links.map(() => {
  const mesh = new T.Mesh(new T.CylinderBufferGeometry(0.006 * size, 0.006 * size, 1, 12),
                          new T.MeshLambertMaterial({ color: 0x555555 }));
  scene.add(mesh);
  return mesh;
});

// --- frames: three axes, x red, y green, z blue -------------------------------------------------------
const frameObjects = data.frames.map((f) => {
  const group = triad(f.size || 0.08 * size);
  scene.add(group);
  return group;
});

// --- a robot's links: a rod from each link's parent frame to its own, a sphere at each joint, ---
// the joint's axis (revolute, continuous, prismatic) an arrow
const ROBOT_LINK = 0x7f7f7f, ROBOT_AXIS = 0xff7f0e;
const robotObjects = ROBOT.map((l) => {
  const rod = new T.Mesh(new T.CylinderBufferGeometry(0.008 * size, 0.008 * size, 1, 12),
                         new T.MeshLambertMaterial({ color: ROBOT_LINK }));
  const joint = new T.Mesh(new T.SphereBufferGeometry(0.014 * size, 16, 12),
                           new T.MeshLambertMaterial({ color: 0x333333 }));
  const moving = l.kind === "revolute" || l.kind === "continuous" || l.kind === "prismatic";
  const axis = moving ? new T.ArrowHelper(new T.Vector3(1, 0, 0), new T.Vector3(), 0.1 * size,
                                          ROBOT_AXIS, 0.03 * size, 0.018 * size) : null;
  scene.add(rod, joint);
  if (axis) scene.add(axis);
  return { rod: rod, joint: joint, axis: axis };
});
// link k's frame in the frames of a sample (-1: the world's)
const WORLD = { pos: new T.Vector3(), quat: new T.Quaternion() };
const linkFrame = (frames, k) => (k >= 0 ? frames[k] : WORLD);
// a robot's contacts: a rod from the link's frame to the contact's point (a last link has no
// child frame to end at; its <visual>, if any, is drawn as well) and the contact's plane, a
// translucent square of the scene's size about the foot of the point at the first sample, fixed
// in the plane's link (the world's: a table)
const ROBOT_CONTACTS = data.robot && data.robot.contacts ? data.robot.contacts : [];
const PLANE_COLOUR = 0xb5a27a;
const robotContactObjects = ROBOT_CONTACTS.map((c) => {
  const rod = c.link >= 0 ? new T.Mesh(new T.CylinderBufferGeometry(0.008 * size, 0.008 * size, 1, 12),
                                       new T.MeshLambertMaterial({ color: ROBOT_LINK })) : null;
  const n = new T.Vector3(...c.plane_normal);
  let patch = null, foot = null;
  // (the world's z = 0 plane, a floor, is the ground grid already)
  const floor = c.plane_link < 0 && n.x === 0 && n.y === 0 && n.z > 0 && c.plane_point[2] === 0;
  if (n.lengthSq() > 0 && robotAt.length && !floor) {
    n.normalize();
    patch = new T.Mesh(new T.PlaneBufferGeometry(size, size),
                       new T.MeshLambertMaterial({ color: PLANE_COLOUR, transparent: true, opacity: 0.35,
                                                   side: T.DoubleSide, depthWrite: false }));
    patch.name = "plane of " + c.name;
    // the foot of the point at the first sample on the plane, in the plane's link's frame
    const f0 = linkFrame(robotAt[0], c.link), p0 = linkFrame(robotAt[0], c.plane_link);
    const w = new T.Vector3(...c.point).applyQuaternion(f0.quat).add(f0.pos);
    const local = w.sub(p0.pos).applyQuaternion(p0.quat.clone().conjugate());
    foot = local.sub(n.clone().multiplyScalar(local.clone().sub(new T.Vector3(...c.plane_point)).dot(n)));
  }
  if (rod) scene.add(rod);
  if (patch) scene.add(patch);
  return { rod: rod, patch: patch, foot: foot, tilt: new T.Quaternion().setFromUnitVectors(new T.Vector3(0, 0, 1), n) };
});
// a rod (a unit cylinder along y) from `from` to `to`; hidden when they coincide
function placeRod(rod, from, to) {
  const d = new T.Vector3().subVectors(to, from), len = d.length();
  rod.visible = len > 1e-9;
  if (!rod.visible) return;
  rod.position.addVectors(from, to).multiplyScalar(0.5);
  rod.quaternion.setFromUnitVectors(new T.Vector3(0, 1, 0), d.divideScalar(len));
  rod.scale.set(1, len, 1);
}
// the visuals, and each loop closure as a dashed line from link_a's frame through its point and
// link_b's point to link_b's frame (not from the world's origin), with a marker at each point:
// a closed chain looks closed
const LOOP_COLOUR = 0x6a3d9a;
for (const r of robotVisuals) {
  if (r.placeholder) r.object.scale.setScalar(0.03 * size);
  scene.add(r.holder);
}
const loopObjects = LOOPS.map(() => {
  const geometry = new T.BufferGeometry();
  geometry.setAttribute("position", new T.BufferAttribute(new Float32Array(12), 3));
  const line = new T.Line(geometry, new T.LineDashedMaterial({ color: LOOP_COLOUR, dashSize: 0.02 * size,
                                                              gapSize: 0.012 * size, depthTest: false }));
  line.frustumCulled = false;
  line.renderOrder = 1;
  const ends = [0, 1].map(() => new T.Mesh(new T.SphereBufferGeometry(0.011 * size, 16, 12),
                                          new T.MeshBasicMaterial({ color: LOOP_COLOUR, depthTest: false })));
  for (const e of ends) e.renderOrder = 1;
  scene.add(line, ...ends);
  return { line: line, ends: ends, points: [] };
});
function drawRobot() {
  const frames = robotAt[frame];
  VISUALS.forEach((v, k) => {
    const holder = robotVisuals[k].holder;
    holder.visible = !!frames;
    if (!frames) return;
    const f = linkFrame(frames, v.link);
    holder.position.copy(f.pos);
    holder.quaternion.copy(f.quat);
  });
  LOOPS.forEach((l, k) => {
    const o = loopObjects[k];
    o.line.visible = o.ends[0].visible = o.ends[1].visible = !!frames;
    if (!frames) return;
    const fa = linkFrame(frames, l.a), fb = linkFrame(frames, l.b);
    const pa = new T.Vector3(...l.point_a).applyQuaternion(fa.quat).add(fa.pos);
    const pb = new T.Vector3(...l.point_b).applyQuaternion(fb.quat).add(fb.pos);
    // (the world's end is its point: no line to the world's origin)
    o.points = [l.a >= 0 ? fa.pos : pa, pa, pb, l.b >= 0 ? fb.pos : pb];
    const position = o.line.geometry.attributes.position;
    o.points.forEach((p, m) => position.setXYZ(m, p.x, p.y, p.z));
    position.needsUpdate = true;
    o.line.computeLineDistances();
    o.ends[0].position.copy(pa);
    o.ends[1].position.copy(pb);
  });
  ROBOT.forEach((l, k) => {
    const o = robotObjects[k];
    o.rod.visible = o.joint.visible = !!frames;
    if (o.axis) o.axis.visible = !!frames;
    if (!frames) return;
    const f = frames[k];
    o.joint.position.copy(f.pos);
    if (o.axis) {
      o.axis.position.copy(f.pos);
      o.axis.setDirection(new T.Vector3(...l.axis).normalize().applyQuaternion(f.quat));
    }
    placeRod(o.rod, l.parent >= 0 ? frames[l.parent].pos : new T.Vector3(), f.pos);
  });
  ROBOT_CONTACTS.forEach((c, k) => {
    const o = robotContactObjects[k];
    if (o.rod) o.rod.visible = !!frames;
    if (o.patch) o.patch.visible = !!frames;
    if (!frames) return;
    if (o.rod) {
      const f = linkFrame(frames, c.link);
      placeRod(o.rod, f.pos, new T.Vector3(...c.point).applyQuaternion(f.quat).add(f.pos));
    }
    if (o.patch) {
      const p = linkFrame(frames, c.plane_link);
      o.patch.position.copy(o.foot).applyQuaternion(p.quat).add(p.pos);
      o.patch.quaternion.copy(p.quat).multiply(o.tilt);
    }
  });
}

// --- joints: markers at the child's point -------------------------------------------------------
const jointMarkers = data.joints.map(() => {
  const mesh = new T.Mesh(new T.SphereBufferGeometry(0.012 * size, 16, 12),
                          new T.MeshLambertMaterial({ color: 0x333333 }));
  scene.add(mesh);
  return mesh;
});
// a joint's axis (revolute: about it; prismatic, cylindrical: along it), shown on request (axes):
// an arrow at the joint's point, the axis of the scene ("axis", in the coordinates of its
// "axis_on" body) turned by that body's pose
const JOINT_AXIS = 0xff7f0e;
const jointAxes = data.joints.map((j) => {
  if (!j.axis) return null;
  const arrow = new T.ArrowHelper(new T.Vector3(0, 0, 1), new T.Vector3(), 0.12 * size, JOINT_AXIS,
                                  0.03 * size, 0.018 * size);
  arrow.visible = false;
  scene.add(arrow);
  return arrow;
});
function jointAxis(j, i, out) {
  const body = j.axis_on === "parent" ? j.parent : j.child, quat = new T.Quaternion();
  if (body !== "ground") bodyPose(data.bodies[bodyIndex.get(body)], i, new T.Vector3(), quat);
  return out.set(...j.axis).normalize().applyQuaternion(quat);
}
function jointPoint(j, i, out) {
  const pos = new T.Vector3(), quat = new T.Quaternion();
  const onChild = j.child !== "ground";
  const body = onChild ? j.child : j.parent;
  const local = new T.Vector3(...(onChild ? j.child_point : j.parent_point));
  if (body === "ground") return out.copy(local);
  bodyPose(data.bodies[bodyIndex.get(body)], i, pos, quat);
  return out.copy(local.applyQuaternion(quat).add(pos));
}

// --- force arrows ----------------------------------------------------------------------------------
// each arrow has a name (its kind, force or torque, and where: "control torque on link1") and,
// in each frame, its magnitude (value, in the page's units: N, N·m) for the readout
const arrows = { ideal: [], nonideal: [], control: [] };
const KIND_NAME = { ideal: "constraint", nonideal: "non-ideal", control: "control", contact: "normal",
                    friction: "friction" };
const arrowName = (kind, torque, where) => KIND_NAME[kind] + (torque ? " torque " : " force ") + where;
// the model's units (data.unit_system when not SI: docs/model-format.md, "Units"); a torque's
// is N·m in SI units, else the energy's
const UNITS = Object.assign({ length: "m", time: "s", force: "N", energy: "J" }, data.unit_system || {});
const TORQUE_UNIT = UNITS.energy === "J" ? "N\u00b7m" : UNITS.energy;
// the unit of the generalized force of coordinates (the force for the length unit, the torque for
// rad and 1: their units in the data), else the force or the torque: a joint's reaction, a
// contact's force
const FORCE_UNIT = { [UNITS.length]: UNITS.force, rad: TORQUE_UNIT, 1: TORQUE_UNIT };
function forceUnit(coordinates, torque) {
  const units = (coordinates || []).map((c) => FORCE_UNIT[data.units[c]]);
  if (units.length && units.every((u) => u && u === units[0])) return units[0];
  return torque ? TORQUE_UNIT : UNITS.force;
}
function addArrow(kind, vectors, where, name, unit) {
  const a = new T.ArrowHelper(new T.Vector3(1, 0, 0), new T.Vector3(), 1, ARROW[kind]);
  a.line.material.linewidth = 2;
  scene.add(a);
  arrows[kind].push({ helper: a, vectors: vectors, where: where, name: arrowName(kind, false, name),
                      value: null, unit: unit || forceUnit(null, false) });
}
// a torque (a joint's reaction torque, its friction torque): an arc of three quarters of a turn
// around the torque's axis, turning as the right-hand rule says, with a head at its end; in the
// colour of its kind, its radius a tenth of the scene for the run's 90th-percentile magnitude
function addTorque(kind, vectors, where, name, unit) {
  // drawn over the solids: the joint's point is usually inside a body
  const material = new T.MeshBasicMaterial({ color: ARROW[kind], depthTest: false });
  const helper = new T.Group();
  // unit radius, in the (x, y) plane, from angle 0 to 3π/2 (counter-clockwise about +z)
  const arc = new T.Mesh(new T.TorusBufferGeometry(1, 0.07, 8, 32, 1.5 * Math.PI), material);
  const head = new T.Mesh(new T.CylinderBufferGeometry(0, 0.22, 0.45, 16), material);
  head.position.set(0.2, -1, 0);    // at angle 3π/2, a little ahead along the turn
  head.rotation.z = -Math.PI / 2;   // the cone's axis (y) along the turn there (+x)
  arc.renderOrder = head.renderOrder = 1;  // after the solids
  helper.add(arc, head);
  scene.add(helper);
  arrows[kind].push({ helper: helper, vectors: vectors, where: where, torque: true,
                      name: arrowName(kind, true, name), value: null, unit: unit || forceUnit(null, true) });
}
// (a body's control torque, planar about z or spatial, is drawn as a joint's torque, at its centre)
for (const kind of ["ideal", "nonideal", "control"]) {
  data.joints.forEach((j) => {
    if (j[kind + "_torque"]) addTorque(kind, j[kind + "_torque"], (i, out) => jointPoint(j, i, out), "at " + j.name);
  });
  data.joints.forEach((j) => { if (j[kind]) addArrow(kind, j[kind], (i, out) => jointPoint(j, i, out), "at " + j.name); });
  data.points.forEach((p) => {
    if (p[kind]) addArrow(kind, p[kind], (i, out) => pointAt(p, i, out), "on " + p.name, forceUnit(p.coordinates, false));
  });
  data.bodies.forEach((b) => {
    const centre = (i, out) => { bodyPose(b, i, out, new T.Quaternion()); return out; };
    const along = (keys) => keys.map((k) => b.name + "." + k);
    if (b[kind]) addArrow(kind, b[kind], centre, "on " + b.name, forceUnit(along(["x", "y"]), false));
    if (b[kind + "_torque"]) {
      const angles = b.kind === "planar" ? ["theta"] : ["u0", "u1", "u2", "u3"];
      addTorque(kind, b[kind + "_torque"], centre, "on " + b.name, forceUnit(along(angles), true));
    }
  });
}
// contacts: a marker at the contact point, the normal force (λ along the normal, λ > 0 pushes)
// an arrow in the contact colour, scaled as the other forces by the run's 90th percentile
const contactPoint = (c, i, out) => {
  if (c.q.some((v) => v[i] === null || v[i] === undefined)) return null;
  return out.set(c.q[0][i], c.q[1][i], c.q.length > 2 ? c.q[2][i] : 0);
};
arrows.contact = [];
arrows.friction = [];
const contactMarkers = CONTACTS.map((c) => {
  const n = c.n.length;
  // the force's components: λ times the unit normal, per frame
  const vectors = [0, 1, 2].slice(0, n).map((a) => c.force.map((f, i) => {
    const len = Math.hypot(...c.n.map((v) => v[i] || 0));
    return f === null || !(len > 0) ? 0 : f * (c.n[a][i] || 0) / len;
  }));
  addArrow("contact", vectors, (i, out) => contactPoint(c, i, out), "at " + c.name);
  // the friction force (a Coulomb contact on it): F less its part along the normal, F − (F·n̂) n̂,
  // a second arrow at the contact point in the friction colour, on the contact force's scale
  if (c.friction_force) {
    const F = c.friction_force;
    const tangential = [0, 1, 2].slice(0, n).map((a) => F[0].map((_, i) => {
      const len = Math.hypot(...c.n.map((v) => v[i] || 0));
      if (!(len > 0)) return 0;
      const along = F.reduce((sum, comp, b) => sum + (comp[i] || 0) * (c.n[b][i] || 0), 0) / len;
      return (F[a][i] || 0) - along * (c.n[a][i] || 0) / len;
    }));
    addArrow("friction", tangential, (i, out) => contactPoint(c, i, out), "at " + c.name);
  }
  const marker = new T.Mesh(new T.SphereBufferGeometry(0.012 * size, 16, 12),
                            new T.MeshBasicMaterial({ color: ARROW.contact, depthTest: false }));
  marker.renderOrder = 1;
  scene.add(marker);
  return marker;
});
// impacts: a ring that flashes out from the contact point for a few frames after each (at most
// RINGS at once: an accumulation of impacts, a bouncing ball coming to rest, reuses them)
const RINGS = 8;
const flash = N > 1 ? Math.max(4 * (data.t[N - 1] - data.t[0]) / (N - 1), 0.02 * (data.t[N - 1] - data.t[0])) : 0;
const impactRings = IMPACTS.length ? Array.from({ length: RINGS }, () => {
  const ring = new T.Mesh(new T.TorusBufferGeometry(1, 0.12, 8, 32),
                          new T.MeshBasicMaterial({ color: IMPACT, depthTest: false, transparent: true }));
  ring.renderOrder = 2;
  ring.visible = false;
  scene.add(ring);
  return ring;
}) : [];
const contactIndex = new Map();
CONTACTS.forEach((c, k) => { contactIndex.set(c.name, k); });
// where contact c is at time t: its point interpolated between the frames around t
function contactAt(c, t, out) {
  let lo = 0, hi = N - 1;
  while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (data.t[mid] <= t) lo = mid; else hi = mid - 1; }
  const a = contactPoint(c, lo, new T.Vector3());
  const b = lo + 1 < N ? contactPoint(c, lo + 1, new T.Vector3()) : null;
  if (!a) return null;
  if (!b || !(data.t[lo + 1] > data.t[lo])) return out.copy(a);
  const s = Math.min(Math.max((t - data.t[lo]) / (data.t[lo + 1] - data.t[lo]), 0), 1);
  return out.copy(a).lerp(b, s);
}
let flashing = 0;  // impact rings shown in this frame
function drawImpacts() {
  flashing = 0;
  impactRings.forEach((r) => { r.visible = false; });
  if (!shown.contact || !IMPACTS.length) return;
  const now = data.t[frame];
  for (let k = IMPACTS.length - 1; k >= 0 && flashing < RINGS; --k) {
    const e = IMPACTS[k], age = now - e.t;
    if (age < 0 || age >= flash || !contactIndex.has(e.contact)) continue;
    const ring = impactRings[flashing];
    if (!contactAt(CONTACTS[contactIndex.get(e.contact)], e.t, ring.position)) continue;
    const r = 0.03 * size * (1 + 2 * age / flash);
    ring.scale.set(r, r, r);
    ring.material.opacity = 1 - 0.7 * age / flash;
    ring.quaternion.copy(data.planar ? new T.Quaternion() : camera.quaternion);
    ring.visible = true;
    flashing += 1;
  }
}
const shown = { ideal: true, nonideal: true, control: true, contact: true, friction: true,
                trails: true, triads: false, axes: false };

// --- trails ----------------------------------------------------------------------------------------
const trails = data.trails.map((name, k) => {
  const positions = new Float32Array(3 * Math.max(N, 1));
  const v = new T.Vector3(), quat = new T.Quaternion();
  let last = null;
  for (let i = 0; i < N; ++i) {
    // where the point is not finite, the trail stays where it last was
    if (positionOf(name, i, v)) last = [v.x, v.y, v.z];
    if (last) positions.set(last, 3 * i);
  }
  const geometry = new T.BufferGeometry();
  geometry.setAttribute("position", new T.BufferAttribute(positions, 3));
  const colour = pointIndex.has(name) ? (data.points[pointIndex.get(name)].color || PALETTE[pointIndex.get(name) % PALETTE.length])
               : bodyIndex.has(name) ? PALETTE[bodyIndex.get(name) % PALETTE.length] : 0x555555;
  const line = new T.Line(geometry, new T.LineBasicMaterial({ color: colour }));
  scene.add(line);
  return line;
});

// --- the requirements' desired paths (controlled models): the whole path dashed, and a ring where --
// the requirement wants its point now (the point's trail is its actual path)
const DESIRED = "#00a651";
const desired = (data.desired_paths || []).map((d) => {
  const at = (i, out) => out.set(d.q[0][i], d.q[1][i], d.q.length > 2 ? d.q[2][i] : 0);
  const positions = new Float32Array(3 * Math.max(N, 1)), v = new T.Vector3();
  for (let i = 0; i < N; ++i) positions.set(at(i, v).toArray(), 3 * i);
  const geometry = new T.BufferGeometry();
  geometry.setAttribute("position", new T.BufferAttribute(positions, 3));
  const path = new T.Line(geometry, new T.LineDashedMaterial({ color: DESIRED, dashSize: 0.02 * size,
                                                                gapSize: 0.015 * size }));
  path.computeLineDistances();
  const ring = new T.Mesh(new T.TorusBufferGeometry(0.03 * size, 0.004 * size, 8, 32),
                          new T.MeshBasicMaterial({ color: DESIRED, depthTest: false }));
  ring.renderOrder = 1;
  if (!data.planar) ring.lookAt(camera.position);
  scene.add(path, ring);
  return { path: path, ring: ring, at: at };
});
// a robot's task-space requirements (pose: rows .0 .1 .2, the point's position minus the desired
// one): the desired path dashed, the point's actual path (desired + error) solid, and the ring
if (ROBOT.length) {
  const rows = new Map();
  for (const r of data.requirements) rows.set(r.name, r);
  for (const r of data.requirements) {
    const m = /^(.*)\.0$/.exec(r.name);
    if (!m) continue;
    const parts = [0, 1, 2].map((k) => rows.get(m[1] + "." + k));
    if (parts.some((x) => !x || !x.desired || !x.actual)) continue;
    const line = (values, material) => {
      const positions = new Float32Array(3 * Math.max(N, 1));
      for (let i = 0; i < N; ++i) positions.set(values.map((c) => c[i] || 0), 3 * i);
      const geometry = new T.BufferGeometry();
      geometry.setAttribute("position", new T.BufferAttribute(positions, 3));
      const l = new T.Line(geometry, material);
      scene.add(l);
      return l;
    };
    const want = parts.map((x) => x.desired), got = parts.map((x) => x.actual);
    const path = line(want, new T.LineDashedMaterial({ color: DESIRED, dashSize: 0.02 * size,
                                                       gapSize: 0.015 * size }));
    path.computeLineDistances();
    trails.push(line(got, new T.LineBasicMaterial({ color: ROBOT_AXIS })));
    const ring = new T.Mesh(new T.TorusBufferGeometry(0.03 * size, 0.004 * size, 8, 32),
                            new T.MeshBasicMaterial({ color: DESIRED, depthTest: false }));
    ring.renderOrder = 1;
    scene.add(ring);
    desired.push({ path: path, ring: ring, at: (i, out) => out.set(want[0][i], want[1][i], want[2][i]) });
  }
}
shown.desired = true;

// --- a frame: move everything to sample i -----------------------------------------------------------
let frame = 0;
function setFrame(i) {
  frame = Math.max(0, Math.min(N - 1, i | 0));
  if (N === 0) return;
  const pos = new T.Vector3(), quat = new T.Quaternion();
  data.bodies.forEach((b, k) => {
    bodyPose(b, frame, pos, quat);
    bodyObjects[k].position.copy(pos);
    bodyObjects[k].quaternion.copy(quat);
  });
  data.points.forEach((p, k) => {
    pointObjects[k].visible = !!pointAt(p, frame, pointObjects[k].position);
  });
  data.frames.forEach((f, k) => {
    frameObjects[k].visible = !!pointAt(f, frame, frameObjects[k].position);
    frameRotation(f, frame, frameObjects[k].quaternion);
  });
  data.links.forEach((l, k) => {
    const a = positionOf(l[0], frame, new T.Vector3()), b = positionOf(l[1], frame, new T.Vector3());
    const mesh = linkObjects[k];
    if (!a || !b) { mesh.visible = false; return; }
    const d = new T.Vector3().subVectors(b, a), len = d.length();
    mesh.visible = len > 0;
    mesh.position.addVectors(a, b).multiplyScalar(0.5);
    if (len > 0) mesh.quaternion.setFromUnitVectors(new T.Vector3(0, 1, 0), d.divideScalar(len));
    mesh.scale.set(1, Math.max(len, 1e-9), 1);
  });
  data.joints.forEach((j, k) => jointPoint(j, frame, jointMarkers[k].position));
  bodyTriads.forEach((axes) => { axes.visible = shown.triads; });
  data.joints.forEach((j, k) => {
    const arrow = jointAxes[k];
    if (!arrow) return;
    arrow.visible = shown.axes;
    arrow.position.copy(jointMarkers[k].position);
    arrow.setDirection(jointAxis(j, frame, new T.Vector3()));
  });
  drawRobot();
  CONTACTS.forEach((c, k) => {
    contactMarkers[k].visible = shown.contact && !!contactPoint(c, frame, contactMarkers[k].position);
  });
  drawImpacts();
  for (const kind of Object.keys(arrows)) {
    for (const a of arrows[kind]) {
      const v = new T.Vector3(...a.vectors.map((c) => (c ? c[frame] || 0 : 0)));
      const at = a.where(frame, new T.Vector3());  // null: a point not finite, hidden
      a.value = at ? v.length() : null;
      if (a.torque) {
        const r = Math.min(v.length() / data.force_scale[kind + "_torque"] * 0.1, 0.2) * size;
        a.helper.visible = shown[kind] && r > 1e-4 * size && !!at;
        if (!a.helper.visible) continue;
        a.helper.position.copy(at);
        a.helper.quaternion.setFromUnitVectors(new T.Vector3(0, 0, 1), v.normalize());
        a.helper.scale.set(r, r, r);
        continue;
      }
      // a quarter of the scene for the run's 90th-percentile magnitude, at most 0.4 of it
      // (friction at contacts on the contact forces' scale)
      const scale = data.force_scale[kind === "friction" ? "contact" : kind];
      const len = Math.min(v.length() / scale * 0.25, 0.4) * size;
      a.helper.visible = shown[kind] && len > 1e-4 * size && !!at;
      if (!a.helper.visible) continue;
      a.helper.position.copy(at);
      a.helper.setDirection(v.normalize());
      a.helper.setLength(len, Math.min(0.3 * len, 0.04 * size), Math.min(0.2 * len, 0.025 * size));
    }
  }
  trails.forEach((line) => { line.visible = shown.trails; line.geometry.setDrawRange(0, frame + 1); });
  desired.forEach((d) => {
    d.path.visible = d.ring.visible = shown.desired;
    d.at(frame, d.ring.position);
    if (!data.planar) d.ring.quaternion.copy(camera.quaternion);
  });
  slider.value = frame;
  const e = data.energy ? data.energy[frame] : null;
  const hits = IMPACTS.filter((h) => h.t <= data.t[frame]).length;
  readout.textContent = "t = " + data.t[frame].toFixed(3) + " " + UNITS.time +
                        (e !== null && e !== undefined ? "   E = " + e.toPrecision(6) + " " + UNITS.energy : "") +
                        (IMPACTS.length ? "   impacts: " + hits : "");
  drawChart();
  drawPaths();
  drawMagnitudes();
  dirty = true;
}

