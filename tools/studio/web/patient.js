// The patient panel: a slider and a field per input; the outputs as `fmpc eval` computes them (the exact text it
// prints, and four digits), each rule's firing strength and contribution ("why this output"), and the aggregated
// output set. Every change asks the server; at most one request is in flight.
"use strict";

Studio.patient = { answer: null, inputsKey: "" };

Studio.patient.evaluate = Studio.latest(async function () {
  const system = Studio.system();
  if (!system) return;
  const started = performance.now();
  try {
    const answer = await Studio.call("/api/evaluate", Studio.rulesRequest({ inputs: Studio.state.patient }));
    answer.milliseconds = performance.now() - started;
    Studio.patient.answer = answer;
    Studio.patient.show(system, answer);
    // The time shown includes drawing the panel, not only the server's answer.
    const hint = document.querySelector("#patient-outputs .hint");
    if (hint) hint.textContent = "updated in " + Math.round(performance.now() - started) + " ms";
    Studio.emit("evaluated", answer);
  } catch (error) {
    Studio.message(error.message, "bad");
  }
});

// Sliders and fields for the system's inputs; values kept across edits while the inputs stay the same.
Studio.patient.buildInputs = function (system) {
  const key = JSON.stringify(system.inputs.map((v) => [v.name, v.min, v.max, v.unit]));
  if (key === Studio.patient.inputsKey) return;
  const previous = {};
  (Studio.patient.names || []).forEach((name, i) => { previous[name] = Studio.state.patient[i]; });
  Studio.patient.inputsKey = key;
  Studio.patient.names = system.inputs.map((v) => v.name);
  Studio.state.patient = system.inputs.map((v) => previous[v.name] !== undefined ? previous[v.name] : (v.min + v.max) / 2);
  const box = document.getElementById("patient-inputs");
  box.replaceChildren(Studio.element("h3", { text: "Patient" }));
  system.inputs.forEach((v, i) => {
    const step = Math.pow(10, Math.floor(Math.log10((v.max - v.min) / 1000)));
    const slider = Studio.element("input", { type: "range", min: String(v.min), max: String(v.max), step: String(step),
      value: String(Studio.state.patient[i]), id: "slider-" + i, "data-input": v.name });
    const field = Studio.element("input", { type: "number", step: "any", value: String(Studio.state.patient[i]), id: "field-" + i, "data-input": v.name });
    slider.addEventListener("input", () => {
      Studio.state.patient[i] = Number(slider.value);
      field.value = slider.value;
      Studio.patient.evaluate();
    });
    field.addEventListener("change", () => {
      const value = Number(field.value);
      if (field.value.trim() === "") return;  // being typed
      if (!Number.isFinite(value)) return Studio.message("give " + v.name + " as a number", "bad");
      Studio.state.patient[i] = value;
      slider.value = field.value;
      Studio.patient.evaluate();
    });
    const unit = v.unit && v.unit !== "dimensionless" ? v.unit : "";
    box.append(Studio.element("div", { class: "patient-input" }, [
      Studio.element("label", { for: "slider-" + i, text: v.name }),
      Studio.element("span", { class: "description", text: (v.description ? v.description + "; " : "") +
        "range " + v.min + " to " + Studio.withUnit(String(v.max), unit) }),
      slider, field, Studio.element("span", { class: "unit", text: unit }),
    ]));
  });
};

// Sets the panel to a patient (from the validation panel) and evaluates it.
Studio.patient.set = function (values) {
  Studio.state.patient = values.slice();
  values.forEach((value, i) => {
    const slider = document.getElementById("slider-" + i), field = document.getElementById("field-" + i);
    if (slider) slider.value = String(value);
    if (field) field.value = String(value);
  });
  Studio.patient.evaluate();
};

Studio.patient.show = function (system, answer) {
  const box = document.getElementById("patient-outputs");
  box.replaceChildren();
  answer.outputs.forEach((out, o) => {
    const variable = system.outputs[o];
    const stage = out.stage ? "stage " + out.stage : "";
    const card = Studio.element("div", { class: "output-card", "data-output": out.name }, [
      Studio.element("div", { class: "label", text: out.name + (variable.description ? ": " + variable.description : "") }),
      Studio.element("div", { class: "value", text: Studio.withUnit(Studio.four(out.value), out.unit) }),
      Studio.element("div", { class: "exact", text: "fmpc eval: " + out.text }),
    ]);
    card.querySelector(".exact").dataset.exact = out.text;
    if (out.interval) card.append(Studio.element("div", { class: "exact", text: "type-reduced interval [" + Studio.four(out.interval[0]) + ", " + Studio.four(out.interval[1]) + "]" }));
    if (stage) card.append(Studio.element("div", { class: "stage", text: stage }));
    if (out.no_rule_fired) card.append(Studio.element("div", { class: "warn", text: "no rule fired: the system's policy gave this value" }));
    box.append(card);
  });
  for (const warning of answer.warnings) box.append(Studio.element("div", { class: "warn", text: warning }));
  box.append(Studio.element("div", { class: "hint", text: "updated in " + Math.round(answer.milliseconds) + " ms" }));
  Studio.patient.contributions(system, answer);
  Studio.patient.aggregate(system, answer);
};

Studio.patient.contributions = function (system, answer) {
  const out = answer.outputs[0];
  const exact = out.method === "exact";
  document.getElementById("contribution-method").textContent = exact
    ? "(Sugeno: each rule's exact share of " + out.name + "; the shares add up to the output)"
    : "(each rule's effect: " + out.name + " minus " + out.name + " without the rule. These do not add up to the output, " +
      "and a rule that fires strongly but has no effect is one whose conclusion other rules already give at least as strongly)";
  const order = system.rules.map((r, i) => i).sort((a, b) =>
    Math.abs(out.contributions[b]) - Math.abs(out.contributions[a]) || answer.firing[b] - answer.firing[a]);
  const all = document.getElementById("show-all-rules").checked;
  // As `fmpc eval --explain`: the rules firing at 0.001 or more, unless every rule is asked for.
  const shown = all ? order : order.filter((i) => answer.firing[i] >= 0.001).slice(0, 15);
  const largest = Math.max.apply(null, shown.map((i) => Math.abs(out.contributions[i])).concat([1e-300]));
  const table = document.getElementById("contribution-table");
  table.replaceChildren(Studio.element("tr", {}, [
    Studio.element("th", { text: "rule" }), Studio.element("th", { text: "firing" }),
    Studio.element("th", { text: (exact ? "share of " : "effect on ") + out.name }), Studio.element("th", { text: "rule" })]));
  for (const i of shown) {
    const c = out.contributions[i];
    const firing = Studio.element("div", { class: "bar firing" });
    firing.style.width = Math.round(answer.firing[i] * 80) + "px";
    const bar = Studio.element("div", { class: "bar " + (c >= 0 ? "up" : "down") });
    bar.style.width = Math.round(Math.abs(c) / largest * 80) + "px";
    const without = out.without && out.policy_without[i] ? " (nothing else fires without it)" : "";
    table.append(Studio.element("tr", { "data-rule": i }, [
      Studio.element("td", { class: "name", text: system.rules[i].name }),
      Studio.element("td", {}, [firing, Studio.element("span", { text: Studio.four(answer.firing[i]) })]),
      Studio.element("td", {}, [bar, Studio.element("span", { text: (c > 0 ? "+" : "") + Studio.withUnit(Studio.four(c), out.unit) + without })]),
      Studio.element("td", { class: "sentence", text: system.rules[i].sentence }),
    ]));
  }
  if (!all && order.length > shown.length)
    table.append(Studio.element("tr", {}, [Studio.element("td", { colspan: "4", class: "hint",
      text: (order.length - shown.length) + " more rules fire below 0.001 or have smaller effects (tick 'show every rule')" })]));
};

Studio.patient.aggregate = function (system, answer) {
  const out = answer.outputs[0];
  const variable = system.outputs[0];
  const svg = document.getElementById("aggregate-chart");
  const unit = out.unit && out.unit !== "dimensionless" ? " (" + out.unit + ")" : "";
  const set = out.set;
  if (system.sugeno) {
    const f = Studio.frame(svg, [variable.min, variable.max], [0, Math.max(1, d3.max(set.membership) || 1)], out.name + unit, "rule weight");
    set.x.forEach((x, k) => f.g.append("line").attr("class", "stem").attr("x1", f.x(x)).attr("x2", f.x(x))
      .attr("y1", f.y(0)).attr("y2", f.y(set.membership[k])));
    f.g.append("line").attr("class", "crisp").attr("x1", f.x(out.value)).attr("x2", f.x(out.value)).attr("y1", 0).attr("y2", f.height);
    return;
  }
  const f = Studio.frame(svg, [variable.min, variable.max], [0, 1.05], out.name + unit, "aggregated grade", { nice: false });
  const area = d3.svg.area().x((d) => f.x(d[0])).y0(f.height).y1((d) => f.y(d[1]));
  f.g.append("path").attr("class", "aggregate").attr("d", area(set.x.map((x, k) => [x, set.membership[k]])));
  if (Number.isFinite(out.value)) {
    f.g.append("line").attr("class", "crisp").attr("x1", f.x(out.value)).attr("x2", f.x(out.value)).attr("y1", 0).attr("y2", f.height);
    f.g.append("text").attr("class", "crisp-label").attr("x", f.x(out.value) + 5).attr("y", 12)
      .text(system.defuzzifier + " = " + Studio.withUnit(Studio.four(out.value), out.unit));
  }
};

Studio.on("model", (system) => {
  Studio.patient.buildInputs(system);
  if (Studio.state.tab === "patient") Studio.patient.evaluate();
});
Studio.on("tab", (tab) => { if (tab === "patient") Studio.patient.evaluate(); });

document.addEventListener("DOMContentLoaded", () => {
  document.getElementById("show-all-rules").addEventListener("change", () => {
    if (Studio.patient.answer && Studio.system()) Studio.patient.contributions(Studio.system(), Studio.patient.answer);
  });
});
