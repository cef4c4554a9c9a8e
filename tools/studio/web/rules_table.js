// The rules as a table in plain language: one row a rule, one column an input or output, the rule as a sentence.
// Changing a cell asks the server to rewrite that rule in the text (only that rule: comments and layout stay).
"use strict";

Studio.rules = {
  // The words a cell may put before a term, grouped in its menu: "F4", "not F4", "very F4", ...
  modifiers: [["", ""], ["not", ""], ["", "very"], ["", "somewhat"], ["", "extremely"], ["", "very very"], ["not", "very"]],
};

Studio.rules.words = function (negated, hedge, term) {
  return (negated ? "not " : "") + (hedge ? hedge + " " : "") + term;
};

// The rule as the server's edit takes it, with the clause on `variable` replaced (value "" removes it).
Studio.rules.specWith = function (rule, role, variable, value, connective, weight) {
  const clause = (c) => ({ variable: c.variable, term: c.term, negated: c.negated, hedge: c.hedge });
  const spec = {
    antecedent: rule.antecedent.map(clause),
    consequent: rule.consequent.map(clause),
    connective: connective || rule.connective,
    weight: weight === undefined ? rule.weight : weight,
  };
  if (role) {
    const list = role === "input" ? spec.antecedent : spec.consequent;
    const at = list.findIndex((c) => c.variable === variable);
    if (value === "") {
      if (at >= 0) list.splice(at, 1);
    } else {
      const [negated, hedge, term] = JSON.parse(value);
      const replacement = { variable: variable, term: term, negated: negated, hedge: hedge };
      if (at >= 0) list[at] = replacement;
      else list.push(replacement);
    }
  }
  return spec;
};

Studio.rules.edit = async function (request) {
  try {
    const answer = await Studio.call("/api/edit", Studio.rulesRequest(request));
    Studio.setText(answer.text);
    Studio.message("", "");
  } catch (error) {
    Studio.message(error.message, "bad");
    Studio.rules.render(Studio.system());  // back to what the text says
  }
};

// A cell: one menu of the variable's terms, plain and with "not" or a hedge; blank for an input the rule ignores.
Studio.rules.cell = function (rule, role, variable) {
  const clauses = role === "input" ? rule.antecedent : rule.consequent;
  const clause = clauses.find((c) => c.variable === variable.name);
  const select = Studio.element("select", { class: "term", title: (role === "input" ? "if " : "then ") + variable.name + " is …" });
  select.append(Studio.element("option", { value: "", text: role === "input" ? "" : "(none)" }));
  for (const [negated, hedge] of Studio.rules.modifiers) {
    const group = negated || hedge ? Studio.element("optgroup", { label: Studio.rules.words(negated, hedge, "…") }) : select;
    for (const term of variable.terms) {
      const value = JSON.stringify([negated === "not", hedge, term.name]);
      group.append(Studio.element("option", { value: value, text: Studio.rules.words(negated, hedge, term.name) }));
    }
    if (group !== select) select.append(group);
  }
  select.value = clause ? JSON.stringify([clause.negated, clause.hedge, clause.term]) : "";
  select.addEventListener("change", () => Studio.rules.edit({
    operation: "set_rule", index: rule.index, rule: Studio.rules.specWith(rule, role, variable.name, select.value),
  }));
  return Studio.element("td", { class: clause ? "set" : "any" }, [select]);
};

Studio.rules.render = function (system) {
  const table = document.getElementById("rule-table");
  table.replaceChildren();
  if (!system) return;
  const filter = document.getElementById("rule-filter").value.trim().toLowerCase();
  const header = Studio.element("tr", {}, [Studio.element("th", { text: "rule" }), Studio.element("th", { text: "" })]);
  for (const v of system.inputs) header.append(Studio.element("th", { class: "input", text: "if " + v.name }));
  for (const v of system.outputs) header.append(Studio.element("th", { class: "output", text: "then " + v.name }));
  header.append(Studio.element("th", { text: "weight" }), Studio.element("th", { text: "reads as" }), Studio.element("th"));
  table.append(Studio.element("thead", {}, [header]));
  const body = Studio.element("tbody");
  let shown = 0;
  for (const rule of system.rules) {
    if (filter && !(rule.name + " " + rule.sentence).toLowerCase().includes(filter)) continue;
    ++shown;
    const connective = Studio.element("select", { class: "connective", title: "how the conditions combine" });
    Studio.fillSelect(connective, ["and", "or"], rule.connective);
    connective.addEventListener("change", () => Studio.rules.edit({
      operation: "set_rule", index: rule.index, rule: Studio.rules.specWith(rule, null, null, null, connective.value),
    }));
    const row = Studio.element("tr", { "data-rule": rule.index }, [
      Studio.element("td", { class: "name", text: rule.name }),
      Studio.element("td", {}, rule.antecedent.length > 1 ? [connective] : []),
    ]);
    for (const v of system.inputs) row.append(Studio.rules.cell(rule, "input", v));
    for (const v of system.outputs) row.append(Studio.rules.cell(rule, "output", v));
    const weight = Studio.element("input", { type: "number", min: "0", max: "1", step: "0.05", value: String(rule.weight), class: "weight" });
    weight.addEventListener("change", () => Studio.rules.edit({
      operation: "set_rule", index: rule.index,
      rule: Studio.rules.specWith(rule, null, null, null, null, Number(weight.value)),
    }));
    row.append(Studio.element("td", {}, [weight]));
    row.append(Studio.element("td", { class: "sentence", text: rule.sentence }));
    row.append(Studio.element("td", {}, [Studio.element("button", {
      class: "delete", text: "×", title: "Delete this rule",
      onclick: () => Studio.rules.edit({ operation: "delete_rule", index: rule.index }),
    })]));
    row.addEventListener("dblclick", () => {
      const position = Studio.position(rule.range.line, rule.range.column);
      Studio.editor.setCursor(position);
      Studio.editor.scrollIntoView(position, 80);
    });
    body.append(row);
  }
  table.append(body);
  document.getElementById("rule-count").textContent =
    (filter ? shown + " of " : "") + system.rules.length + " rule" + (system.rules.length === 1 ? "" : "s");
};

// Re-drawn only when the rules or the variables changed (a comment typed in the editor leaves the table alone).
Studio.on("model", (system) => {
  const key = JSON.stringify([system.name, system.rules, system.inputs.map((v) => v.terms.map((t) => t.name)),
    system.outputs.map((v) => v.terms.map((t) => t.name))]);
  if (key === Studio.rules.renderedKey) return;
  Studio.rules.renderedKey = key;
  Studio.rules.render(system);
});
Studio.on("broken", () => {
  Studio.rules.renderedKey = null;
  const table = document.getElementById("rule-table");
  table.replaceChildren(Studio.element("tr", {}, [Studio.element("td", { class: "broken",
    text: "The text has errors (listed under the editor): fix them to see and edit the rules here." })]));
});

document.addEventListener("DOMContentLoaded", () => {
  document.getElementById("rule-filter").addEventListener("input", () => Studio.rules.render(Studio.system()));
  Studio.on("file", () => { Studio.rules.renderedKey = null; });
  document.getElementById("add-rule").addEventListener("click", () => Studio.rules.edit({ operation: "add_rule" }));
});
