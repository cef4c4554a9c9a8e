// The patient's scene: the server runs it on the CPU with this edit's rules and the patient panel's inputs (the demo's
// liver block indented by a probe, or a scene of the folder); the page draws the probe's force against its
// displacement and the tissue in 3-D (Debian's three.js, libjs-three), coloured by how far each point moved.
"use strict";

Studio.scene = { answer: null, renderer: null };

Studio.scene.run = async function () {
  const status = document.getElementById("scene-status"), errors = document.getElementById("scene-errors");
  if (!Studio.system()) {
    errors.replaceChildren(Studio.element("pre", { text: "The text has errors (listed under the editor): fix them first." }));
    return;
  }
  status.textContent = "running the scene…";
  document.getElementById("scene-run").disabled = true;
  try {
    const answer = await Studio.call("/api/scene", Studio.rulesRequest({
      inputs: Studio.state.patient, scene: document.getElementById("scene-select").value,
    }));
    errors.replaceChildren();
    Studio.scene.answer = answer;
    Studio.scene.show(answer);
    status.textContent = "";
  } catch (error) {
    status.textContent = "";
    errors.replaceChildren(Studio.element("pre", { text: error.message }));
  } finally {
    document.getElementById("scene-run").disabled = false;
  }
};

// The runtime's description of the material writes its modulus with every digit (20.8283800234838 kPa): four
// significant digits here, as the patient panel shows its output.
Studio.scene.shortNumbers = function (text) {
  return text.replace(/-?\d+\.\d{5,}(e[-+]?\d+)?/g, (number) => Studio.four(Number(number)));
};

Studio.scene.show = function (answer) {
  document.getElementById("scene-results").hidden = false;
  const patient = Studio.system().inputs.map((v, i) => v.name + " " + Studio.withUnit(String(Studio.state.patient[i]), v.unit)).join(", ");
  document.getElementById("scene-summary").textContent =
    answer.scene + ": " + Studio.scene.shortNumbers(answer.stiffness) + (answer.patient_and_rules_used ? " (this edit's rules, patient " + patient + ")"
      : " (the scene's own rules and inputs: its material names " + answer.rules + ")") + ". " + answer.steps +
    " steps of " + Studio.four(answer.time_step * 1000) + " ms in " + Studio.four(answer.wall_seconds) + " s; the largest displacement " +
    Studio.four(answer.max_displacement * 1000) + " mm." + (answer.completed ? "" : " The run stopped early: see the messages.");
  if (answer.warnings) document.getElementById("scene-errors").replaceChildren(Studio.element("pre", { text: answer.warnings }));
  const curve = answer.probe_curve;
  const svg = document.getElementById("scene-curve");
  if (curve.length) {
    const f = Studio.frame(svg, Studio.padded(curve.map((p) => p[1] * 1000)), Studio.padded(curve.map((p) => p[2]).concat([0])),
      "probe displacement (mm)", "probe force (N)", { title: "Probe force against displacement" });
    const line = d3.svg.line().x((p) => f.x(p[1] * 1000)).y((p) => f.y(p[2]));
    f.g.append("path").attr("class", "curve").attr("d", line(curve));
  } else {
    d3.select(svg).selectAll("*").remove();
    d3.select(svg).append("text").attr("x", 20).attr("y", 40).text("This scene has no probe: no force curve.");
  }
  Studio.scene.draw(answer);
};

Studio.scene.draw = function (answer) {
  const view = document.getElementById("scene-view");
  view.replaceChildren();
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (error) {
    view.append(Studio.element("p", { class: "warn", text: "The 3-D view needs WebGL, which this browser does not offer." }));
    return;
  }
  const width = 420, height = 360;
  renderer.setSize(width, height);
  renderer.setClearColor(0xffffff);
  view.append(renderer.domElement);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(35, width / height, 0.1, 10000);
  camera.up.set(0, 0, 1);
  const mm = (flat) => Float32Array.from(flat, (c) => c * 1000);
  const rest = mm(answer.rest), final = mm(answer.final);
  const count = rest.length / 3;
  const moved = new Float32Array(count);
  let largest = 0;
  for (let v = 0; v < count; ++v) {
    moved[v] = Math.hypot(final[3 * v] - rest[3 * v], final[3 * v + 1] - rest[3 * v + 1], final[3 * v + 2] - rest[3 * v + 2]);
    largest = Math.max(largest, moved[v]);
  }
  const colours = new Float32Array(3 * count);
  for (let v = 0; v < count; ++v) colours.set(Studio.viridis(largest > 0 ? moved[v] / largest : 0), 3 * v);
  const surface = (positions, coloured) => {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
    if (coloured) geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
    geometry.setIndex(answer.triangles);
    geometry.computeVertexNormals();
    return geometry;
  };
  const deformed = surface(final, true);
  scene.add(new THREE.Mesh(deformed, new THREE.MeshLambertMaterial({ vertexColors: THREE.VertexColors, side: THREE.DoubleSide })));
  scene.add(new THREE.LineSegments(new THREE.WireframeGeometry(deformed), new THREE.LineBasicMaterial({ color: 0x333333, transparent: true, opacity: 0.25 })));
  const restMesh = new THREE.LineSegments(new THREE.WireframeGeometry(surface(rest, false)),
    new THREE.LineBasicMaterial({ color: 0xd62728, transparent: true, opacity: 0.35 }));
  restMesh.visible = document.getElementById("scene-show-rest").checked;
  scene.add(restMesh);
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  const light = new THREE.DirectionalLight(0xffffff, 0.6);
  light.position.set(1, -2, 3);
  scene.add(light);
  deformed.computeBoundingBox();
  const box = deformed.boundingBox, centre = new THREE.Vector3();
  box.getCenter(centre);
  const size = box.getSize(new THREE.Vector3()).length();
  camera.position.set(centre.x + size * 0.9, centre.y - size * 1.4, centre.z + size * 1.0);
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();
  const render = () => renderer.render(scene, camera);
  controls.addEventListener("change", render);
  document.getElementById("scene-show-rest").onchange = (event) => { restMesh.visible = event.target.checked; render(); };
  render();
  view.append(Studio.element("div", { class: "hint", text: "Colour: displacement, 0 (dark) to " + Studio.four(largest) +
    " mm (yellow). Drag to turn the tissue, scroll to zoom." }));
};

Studio.on("session", (session) => {
  const scenes = [{ value: "", label: "Demo: a liver block indented by a probe" }]
    .concat(session.files.filter((f) => /\.ya?ml$/.test(f)));
  Studio.fillSelect(document.getElementById("scene-select"), scenes, "");
});

document.addEventListener("DOMContentLoaded", () => {
  document.getElementById("scene-run").addEventListener("click", Studio.scene.run);
});
