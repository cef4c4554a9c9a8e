// Validation against measured data (as `fmpc validate`): a CSV chosen here or in the folder, its columns mapped to
// the inputs and the measured output, and the server's report: MAE, RMSE, bias, limits of agreement, predicted
// against measured, Bland-Altman, and the worst patients, each one click from the patient panel.
"use strict";

Studio.validation = { csv: null, mapping: {}, measured: "", output: "" };

// The header's column names without a stated unit ("HCV (kPa)" is column HCV), as the server reads them.
Studio.csvColumns = function (text) {
  const line = text.split(/\r?\n/)[0] || "";
  const cells = [];
  let cell = "", quoted = false;
  for (const ch of line) {
    if (ch === '"') quoted = !quoted;
    else if (ch === "," && !quoted) { cells.push(cell); cell = ""; }
    else cell += ch;
  }
  cells.push(cell);
  return cells.map((c) => c.trim().replace(/\s*[(\[][^)\]]*[)\]]$/, ""));
};

// A CSV from the file picker or the folder, then `then(csv)`.
Studio.loadCsv = function (fileInput, folderSelect, then) {
  fileInput.addEventListener("change", () => {
    const file = fileInput.files[0];
    if (!file) return;
    const reader = new FileReader();
    reader.onload = () => then({ name: file.name, text: reader.result });
    reader.readAsText(file);
  });
  folderSelect.addEventListener("change", async () => {
    if (!folderSelect.value) return;
    try {
      const file = await Studio.call("/api/file?path=" + encodeURIComponent(folderSelect.value));
      then({ name: file.path, text: file.text });
    } catch (error) {
      Studio.message(error.message, "bad");
    }
  });
};

Studio.on("session", (session) => {
  const csvs = [{ value: "", label: "(choose)" }].concat(session.files.filter((f) => f.endsWith(".csv")));
  Studio.fillSelect(document.getElementById("validation-folder-file"), csvs, "");
  Studio.fillSelect(document.getElementById("compare-folder-file"), csvs, "");
});

Studio.validation.mappingUi = function () {
  const v = Studio.validation, system = Studio.system();
  const box = document.getElementById("validation-mapping");
  box.replaceChildren();
  if (!v.csv || !system) return;
  const columns = Studio.csvColumns(v.csv.text);
  const row = Studio.element("div", { class: "mapping" }, [Studio.element("span", { class: "hint", text: v.csv.name + ": " })]);
  for (const input of system.inputs) {
    const select = Studio.element("select", { "data-input": input.name });
    const chosen = v.mapping[input.name] || (columns.includes(input.name) ? input.name : "");
    Studio.fillSelect(select, [{ value: "", label: "(missing)" }].concat(columns), chosen);
    select.addEventListener("change", () => { v.mapping[input.name] = select.value; Studio.validation.run(); });
    row.append(Studio.element("label", {}, [input.name + " from ", select]));
  }
  if (system.outputs.length > 1) {
    const output = Studio.element("select", {});
    Studio.fillSelect(output, system.outputs.map((o) => o.name), v.output || system.outputs[0].name);
    output.addEventListener("change", () => { v.output = output.value; Studio.validation.run(); });
    row.append(Studio.element("label", {}, ["output ", output]));
  }
  const measured = Studio.element("select", { id: "validation-measured" });
  Studio.fillSelect(measured, [{ value: "", label: "(automatic)" }].concat(columns), v.measured);
  measured.addEventListener("change", () => { v.measured = measured.value; Studio.validation.run(); });
  row.append(Studio.element("label", {}, ["measured values from ", measured]));
  box.append(row);
};

Studio.validation.run = Studio.latest(async function () {
  const v = Studio.validation, system = Studio.system();
  if (!v.csv || !system) return;
  const columns = {};
  for (const [input, column] of Object.entries(v.mapping))
    if (column && column !== input && system.inputs.some((i) => i.name === input)) columns[input] = column;
  const errors = document.getElementById("validation-errors");
  try {
    const answer = await Studio.call("/api/validate", Studio.rulesRequest({
      csv: { name: v.csv.name, text: v.csv.text, columns: columns }, output: v.output, measured: v.measured,
    }));
    errors.replaceChildren();
    if (!answer.ok) {
      document.getElementById("validation-results").hidden = true;
      for (const text of answer.errors) errors.append(Studio.element("pre", { text: text }));
      return;
    }
    Studio.validation.show(system, answer);
  } catch (error) {
    errors.replaceChildren(Studio.element("pre", { text: error.message }));
  }
});

Studio.validation.show = function (system, answer) {
  document.getElementById("validation-results").hidden = false;
  const a = answer.agreement;
  const cards = document.getElementById("validation-cards");
  const card = (label, value, id) => Studio.element("div", { class: "card", id: id || "" },
    [Studio.element("div", { class: "label", text: label }), Studio.element("div", { class: "value", text: value })]);
  cards.replaceChildren(
    card("patients", String(a.count), "validation-count"),
    card("mean absolute error (MAE)", a.mae.text, "validation-mae"),
    card("root mean square error", a.rmse.text, "validation-rmse"),
    card("bias (predicted − measured)", a.bias.text, "validation-bias"),
    card("95% limits of agreement", a.count < 2 ? "undefined" : a.lower_limit.text + " to " + a.upper_limit.text),
    card("Pearson r", a.correlation.value === null ? "undefined" : a.correlation.text));
  const unit = answer.unit && answer.unit !== "dimensionless" ? " (" + answer.unit + ")" : "";
  const p = answer.patients;
  // Predicted against measured, on equal axes, with the line where they agree.
  const span = Studio.padded(p.map((q) => q.measured).concat(p.map((q) => q.predicted)));
  const s = Studio.frame(document.getElementById("validation-scatter"), span, span, "measured " + answer.output + unit,
    "predicted " + answer.output + unit, { title: "Predicted against measured" });
  s.g.append("line").attr("class", "identity").attr("x1", s.x(s.x.domain()[0])).attr("y1", s.y(s.x.domain()[0]))
    .attr("x2", s.x(s.x.domain()[1])).attr("y2", s.y(s.x.domain()[1]));
  const dot = (g, x, y, q, i) => g.append("circle").attr("class", "dot" + (answer.worst.slice(0, 3).includes(i) ? " worst" : ""))
    .attr("cx", x).attr("cy", y).attr("r", 4).on("click", () => Studio.validation.open(q))
    .append("title").text(q.label + ": measured " + q.measured + ", predicted " + Studio.four(q.predicted));
  p.forEach((q, i) => dot(s.g, s.x(q.measured), s.y(q.predicted), q, i));
  // Bland-Altman: the difference against the mean of the two, with the bias and the limits of agreement.
  const levels = [a.bias.value].concat(a.count < 2 ? [] : [a.lower_limit.value, a.upper_limit.value]);
  const b = Studio.frame(document.getElementById("validation-bland-altman"), Studio.padded(p.map((q) => q.mean)),
    Studio.padded(p.map((q) => q.difference).concat(levels).concat([0])), "mean of predicted and measured" + unit,
    "predicted − measured" + unit, { title: "Bland-Altman" });
  levels.forEach((level, k) => {
    b.g.append("line").attr("class", k === 0 ? "bias" : "limit").attr("x1", 0).attr("x2", b.width)
      .attr("y1", b.y(level)).attr("y2", b.y(level));
    b.g.append("text").attr("class", "level-label").attr("x", b.width - 4).attr("y", b.y(level) - 4).attr("text-anchor", "end")
      .text((k === 0 ? "bias " : k === 1 ? "−1.96 SD " : "+1.96 SD ") + Studio.four(level));
  });
  p.forEach((q, i) => dot(b.g, b.x(q.mean), b.y(q.difference), q, i));
  const table = document.getElementById("validation-worst");
  table.replaceChildren(Studio.element("tr", {}, ["patient", "measured" + unit, "predicted" + unit, "difference" + unit, "strongest rule (firing)", ""]
    .map((h) => Studio.element("th", { text: h }))));
  for (const i of answer.worst) {
    const q = p[i];
    table.append(Studio.element("tr", {}, [
      Studio.element("td", { text: q.label }), Studio.element("td", { text: Studio.four(q.measured) }),
      Studio.element("td", { text: Studio.four(q.predicted) }), Studio.element("td", { text: Studio.four(q.difference) }),
      Studio.element("td", { text: q.strongest_rule < 0 ? "none fired" : q.strongest_rule_name + " (" + Studio.four(q.strongest_firing) + ")" }),
      Studio.element("td", {}, [Studio.element("button", { text: "Show in patient panel", onclick: () => Studio.validation.open(q) })]),
    ]));
  }
  const notes = document.getElementById("validation-notes");
  notes.replaceChildren();
  for (const note of answer.notes.concat(answer.warnings)) notes.append(Studio.element("li", { text: note }));
};

// A patient of the table in the patient panel: its inputs, its outputs and every rule's firing.
Studio.validation.open = function (patient) {
  Studio.showTab("patient");
  Studio.patient.set(patient.inputs);
};

Studio.on("model", () => {
  if (!Studio.validation.csv) return;
  if (!document.getElementById("validation-mapping").children.length) Studio.validation.mappingUi();
  Studio.validation.run();
});

document.addEventListener("DOMContentLoaded", () => {
  Studio.loadCsv(document.getElementById("validation-file"), document.getElementById("validation-folder-file"), (csv) => {
    Studio.validation.csv = csv;
    Studio.validation.mapping = {};
    Studio.validation.measured = "";
    Studio.validation.mappingUi();
    Studio.validation.run();
  });
});
