/* The jax3dc viewer: the object described by the page's JSON (script#jax3dc-data, written by
   jax3dc.viewer.page) in 3D, a slider per joint limited to its range, the physics verdict per
   joint, the images I and S, the parts and the relations. Data is only ever put in the page as
   text (textContent), never as markup: part names and descriptions come from a model's output.
   Needs the global THREE of three.bundle.min.js (three.js + GLTFLoader + OrbitControls). */
(function () {
  "use strict";
  const data = JSON.parse(document.getElementById("jax3dc-data").textContent);
  const BACKGROUND = 0xf4f4f4;
  const HIGHLIGHT = new THREE.Color(0x7a5a00);  // emissive of hovered and related parts
  const NO_GLOW = new THREE.Color(0x000000);
  const FLAG_COLOUR = 0xdd2222;
  const AXIS_COLOURS = { hinge: 0xff8800, slide: 0x0077ff };
  const STEPS = 500;  // slider positions across a joint's range
  const OBJECT_COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf"];  // a scene's objects in the part list

  function el(tag, attrs, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
    for (const c of children) e.append(c);
    return e;
  }

  function bytesOf(base64) {
    const text = atob(base64);
    const out = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) out[i] = text.charCodeAt(i);
    return out.buffer;
  }

  const clamp = (x, lo, hi) => Math.min(hi, Math.max(lo, x));
  const fmt = (x) => Number(x).toFixed(3);

  function partText(p) {
    const m = p.material;
    const material = m ? ` (${m.family}${m.desc ? ": " + m.desc : ""})` : "";
    return `part ${p.id}${p.name ? " " + p.name : ""}${material}`;
  }

  function jointCheck(id) {
    if (!data.verdict) return null;
    return data.verdict.joints[String(id)] || null;
  }

  // --- renderer, scene, camera ------------------------------------------------------------------
  const view = document.getElementById("view");
  const canvas = document.getElementById("canvas");
  const status = document.getElementById("status");
  const tooltip = document.getElementById("tooltip");
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(BACKGROUND);
  const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
  camera.up.set(0, 0, 1);  // the object frame is +Z up (SPEC §2)
  const sky = new THREE.HemisphereLight(0xffffff, 0x777777, 1.5);
  sky.position.set(0, 0, 1);
  scene.add(sky);
  const headlight = new THREE.DirectionalLight(0xffffff, 1.5);
  const ahead = new THREE.Object3D();
  headlight.position.set(0.4, 0.6, 0);
  ahead.position.set(0, 0, -1);
  camera.add(headlight, ahead);
  headlight.target = ahead;
  scene.add(camera);

  function render() { renderer.render(scene, camera); }

  function resize() {
    const w = Math.max(1, canvas.clientWidth), h = Math.max(1, canvas.clientHeight);
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    render();
  }

  // --- the object -------------------------------------------------------------------------------
  const nodes = new Map();         // part id -> its glTF node
  const meshes = new Map();        // part id -> the meshes that draw it (own material each)
  const decorations = new Map();   // part id -> helpers drawn with it (flag box)
  const hot = new Set();           // highlighted part ids
  const joints = [];

  function ownerId(object) {
    for (let o = object; o; o = o.parent) if (o.userData && o.userData.part_id !== undefined) return o.userData.part_id;
    return null;
  }

  function collectParts(root) {
    root.traverse((o) => { if (o.userData && o.userData.part_id !== undefined) nodes.set(o.userData.part_id, o); });
    root.traverse((o) => {
      if (!o.isMesh) return;
      const id = ownerId(o);
      if (id === null) return;
      o.material = o.material.clone();  // parts sharing a glTF material still highlight alone
      o.material.metalness = Math.min(o.material.metalness, 0.4);  // no environment map to reflect
      if (!meshes.has(id)) meshes.set(id, []);
      meshes.get(id).push(o);
    });
  }

  function partBox(id) {
    const node = nodes.get(id), box = new THREE.Box3();
    for (const m of meshes.get(id) || []) {
      m.geometry.computeBoundingBox();
      const b = m.geometry.boundingBox.clone();
      for (let o = m; o !== node; o = o.parent) b.applyMatrix4(o.matrix);
      box.union(b);
    }
    return box;
  }

  function setJoint(joint, q) {
    joint.q = clamp(q, joint.lo, joint.hi);
    if (joint.type === "hinge") {
      const turn = new THREE.Quaternion().setFromAxisAngle(joint.axis, joint.q);
      joint.node.quaternion.copy(turn).multiply(joint.restQuaternion);
      joint.node.position.copy(joint.restPosition);
    } else {
      joint.node.position.copy(joint.restPosition).addScaledVector(joint.axis, joint.q);
    }
    joint.node.updateMatrixWorld(true);
    joint.slider.value = String(joint.q);
    joint.readout.textContent = `q = ${fmt(joint.q)} ${joint.unit}`;
  }

  function highlight(ids) {
    hot.clear();
    for (const id of ids) hot.add(id);
    for (const [id, list] of meshes) for (const m of list) m.material.emissive.copy(hot.has(id) ? HIGHLIGHT : NO_GLOW);
    for (const li of document.querySelectorAll("[data-part]")) li.classList.toggle("hot", hot.has(Number(li.dataset.part)));
    for (const li of document.querySelectorAll("#relations li")) {
      li.classList.toggle("hot", ids.length > 0 && ids.includes(Number(li.dataset.a)) && ids.includes(Number(li.dataset.b)));
    }
    render();
  }

  function showOnly(ids) {  // null: every part (used to see one part's pixels alone)
    for (const [id, list] of meshes) {
      const shown = ids === null || ids.includes(id);
      for (const m of list) m.material.visible = shown;
      for (const d of decorations.get(id) || []) d.visible = shown;
    }
    render();
  }

  function fitCamera(root) {
    const box = new THREE.Box3().setFromObject(root);
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6);
    const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.05;
    camera.position.copy(centre).addScaledVector(new THREE.Vector3(0.55, -1.0, 0.5).normalize(), distance);
    camera.near = distance / 100;
    camera.far = distance * 100;
    camera.lookAt(centre);
    camera.updateProjectionMatrix();
    return { centre, radius };
  }

  function addAxisHelpers(joint, radius) {
    const length = radius * 0.6, colour = AXIS_COLOURS[joint.type];
    const group = new THREE.Group();
    group.add(new THREE.ArrowHelper(joint.axis, new THREE.Vector3(), length, colour, length * 0.2, length * 0.1));
    const pivot = new THREE.Mesh(new THREE.SphereGeometry(radius * 0.025, 16, 12), new THREE.MeshBasicMaterial({ color: colour }));
    group.add(pivot);
    group.traverse((o) => { if (o.material) { o.material.depthTest = false; o.renderOrder = 10; } });  // seen through parts
    group.position.copy(joint.restPosition);  // the pivot, in the parent part's frame: it stays with the parent
    group.visible = false;
    joint.node.parent.add(group);
    return group;
  }

  // --- side panel -------------------------------------------------------------------------------
  function hoverPart(element, ids) {
    element.addEventListener("mouseenter", () => highlight(ids));
    element.addEventListener("mouseleave", () => highlight([]));
  }

  function fillImages() {
    const box = document.getElementById("images");
    for (const image of data.images) box.append(el("figure", {}, el("img", { src: image.src, alt: image.caption }),
      el("figcaption", {}, image.caption)));
  }

  function jointRow(joint) {
    const p = joint.part, check = jointCheck(p.id);
    const flagged = check !== null && !check.ok;
    const row = el("div", { class: "joint" + (flagged ? " flagged" : ""), "data-joint": String(p.id) });
    const warned = check !== null && check.ok && check.warnings.length > 0;
    const state = check === null ? el("span", { class: "muted" }, "not checked")
      : flagged ? el("span", { class: "flag" }, "flagged")
      : warned ? el("span", { class: "warn" }, "ok, with a warning") : el("span", { class: "pass" }, "ok");
    const title = el("div", {}, `${joint.type} of part ${p.id}${p.name ? " " + p.name : ""} · `, state);
    joint.slider = el("input", { type: "range", min: String(joint.lo), max: String(joint.hi),
      step: String((joint.hi - joint.lo) / STEPS || 1), value: String(joint.rest), "aria-label": `joint of part ${p.id}` });
    if (joint.hi <= joint.lo) joint.slider.disabled = true;
    joint.readout = el("span", {});
    const limits = el("span", { class: "muted" }, ` range [${fmt(joint.lo)}, ${fmt(joint.hi)}] ${joint.unit}`);
    row.append(title, joint.slider, el("div", {}, joint.readout, limits));
    if (flagged) {
      const reasons = el("ul", { class: "reasons" });
      for (const r of check.reasons) reasons.append(el("li", {}, r));
      row.append(reasons);
    }
    if (check !== null && check.warnings.length > 0) {
      const warnings = el("ul", { class: "warnings" });
      for (const w of check.warnings) warnings.append(el("li", {}, w));
      row.append(warnings);
    }
    joint.slider.addEventListener("input", () => { setJoint(joint, Number(joint.slider.value)); render(); });
    hoverPart(row, [p.id]);
    return row;
  }

  function fillPhysics() {
    const box = document.getElementById("physics"), badge = document.getElementById("verdict-badge");
    const v = data.verdict;
    if (!v) {
      box.append(el("p", { class: "muted" }, "not checked (no physics.json)"));
      badge.append(el("span", { class: "muted" }, "physics: not checked"));
      return;
    }
    const flagged = Object.entries(v.joints).filter(([, j]) => !j.ok).map(([id]) => id);
    const summary = v.ok ? "PASS" : "FAIL";
    const detail = flagged.length ? ` (joints of parts ${flagged.join(", ")} flagged)` : "";
    badge.append(el("span", { class: v.ok ? "pass" : "fail" }, `physics: ${summary}`), detail);
    box.append(el("p", {}, el("span", { class: v.ok ? "pass" : "fail" }, summary), detail));
    const checks = el("ul", {});
    for (const [name, items] of Object.entries(v.checks)) checks.append(el("li", {}, `${name}: ${items.join("; ")}`));
    if (checks.childElementCount) box.append(checks);
  }

  function partRow(p) {
    const colour = (meshes.get(p.id) || [])[0];
    const swatch = el("span", { class: "swatch" });
    if (colour) swatch.style.background = "#" + colour.material.color.getHexString();
    const how = p.parent === null ? "root" : p.joint ? `${p.joint.type} on part ${p.parent}` : `rigid on part ${p.parent}`;
    const li = el("li", { "data-part": String(p.id) }, swatch, `${partText(p)} · ${how}`);
    hoverPart(li, [p.id]);
    return li;
  }

  function fillParts() {  // a scene (several trees, SPEC §2): one group per object, hovering it lights the object
    const list = document.getElementById("parts");
    const objects = new Map();
    for (const p of data.parts) {
      if (!objects.has(p.object)) objects.set(p.object, []);
      objects.get(p.object).push(p);
    }
    if (objects.size === 1) {
      for (const p of data.parts) list.append(partRow(p));
      return;
    }
    let k = 0;
    for (const [root, members] of objects) {
      const heading = el("div", { class: "object-heading" }, `object ${root} · ${members.length} part${members.length > 1 ? "s" : ""}`);
      hoverPart(heading, members.map((p) => p.id));
      const inner = el("ul", {});
      for (const p of members) inner.append(partRow(p));
      const group = el("li", { class: "object", "data-object": String(root) }, heading, inner);
      group.style.borderLeftColor = OBJECT_COLOURS[k++ % OBJECT_COLOURS.length];
      list.append(group);
    }
  }

  function fillRelations() {
    const list = document.getElementById("relations");
    if (!data.relations.length) list.append(el("li", { class: "muted" }, "none"));
    for (const r of data.relations) {
      const li = el("li", { "data-a": String(r.a), "data-b": String(r.b) },
        `${r.type} ${r.a} – ${r.b}${r.plane ? ` (plane ${r.plane})` : ""}`);
      hoverPart(li, [r.a, r.b]);
      list.append(li);
    }
  }

  // --- pointer: name the part under the cursor ---------------------------------------------------
  const raycaster = new THREE.Raycaster();
  function onPointerMove(event) {
    const rect = canvas.getBoundingClientRect();
    const at = new THREE.Vector2((event.clientX - rect.left) / rect.width * 2 - 1, -(event.clientY - rect.top) / rect.height * 2 + 1);
    raycaster.setFromCamera(at, camera);
    const targets = [].concat(...meshes.values()).filter((m) => m.material.visible);
    const hit = raycaster.intersectObjects(targets, false)[0];
    const id = hit ? ownerId(hit.object) : null;
    if (id === null) {
      tooltip.hidden = true;
      if (hot.size) highlight([]);
      return;
    }
    tooltip.textContent = partText(data.parts.find((p) => p.id === id));
    tooltip.style.left = `${event.clientX - rect.left + 12}px`;
    tooltip.style.top = `${event.clientY - rect.top + 12}px`;
    tooltip.hidden = false;
    if (!(hot.size === 1 && hot.has(id))) highlight([id]);
  }

  function start(root) {
    scene.add(root);
    collectParts(root);
    const { centre, radius } = fitCamera(root);
    const controls = new THREE.OrbitControls(camera, canvas);
    controls.target.copy(centre);
    controls.update();
    controls.addEventListener("change", render);
    const jointsBox = document.getElementById("joints");
    for (const p of data.parts) {
      if (!p.joint || !nodes.has(p.id)) continue;
      const [lo, hi] = p.joint.range;
      const node = nodes.get(p.id);
      const joint = { part: p, node, type: p.joint.type, lo, hi, rest: clamp(0, lo, hi), q: 0,
        unit: p.joint.range_unit || (p.joint.type === "hinge" ? "rad" : "m"),
        axis: new THREE.Vector3(...p.joint.axis).normalize(),
        restPosition: node.position.clone(), restQuaternion: node.quaternion.clone() };
      joint.helpers = addAxisHelpers(joint, radius);
      jointsBox.append(jointRow(joint));
      setJoint(joint, joint.rest);
      joints.push(joint);
      const check = jointCheck(p.id);
      if (check && !check.ok) {
        const flag = new THREE.Box3Helper(partBox(p.id), FLAG_COLOUR);
        node.add(flag);
        decorations.set(p.id, [flag]);
      }
    }
    if (!joints.length) jointsBox.append(el("p", { class: "muted" }, "no joints: every part is rigid"));
    document.getElementById("rest").addEventListener("click", () => { for (const j of joints) setJoint(j, j.rest); render(); });
    document.getElementById("show-axes").addEventListener("change", (e) => {
      for (const j of joints) j.helpers.visible = e.target.checked;
      render();
    });
    fillParts();
    fillRelations();
    canvas.addEventListener("pointermove", onPointerMove);
    canvas.addEventListener("pointerleave", () => { tooltip.hidden = true; if (hot.size) highlight([]); });
    window.addEventListener("resize", resize);
    status.hidden = true;
    resize();
    window.jax3dcViewer = { scene, camera, render, showOnly, highlight,
      setJoint: (id, q) => { setJoint(joints.find((j) => j.part.id === id), q); render(); } };
    document.body.dataset.ready = "true";
  }

  fillImages();
  fillPhysics();
  new THREE.GLTFLoader().parse(bytesOf(data.glb), "", (gltf) => start(gltf.scene), (error) => {
    status.textContent = `could not load the object: ${error.message || error}`;
    console.error(error);
  });
})();
