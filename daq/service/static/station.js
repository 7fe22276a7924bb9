/* The test station's parts of the live page (index.html): named setups and their editor,
 * the transducers, practice hits (auto-range), and the test and point a capture is for.
 *
 * Routes (each feature hides itself while the service lacks its route):
 *   GET /api/setups, GET/PUT /api/setups/{name}     (PUT {setup, version}; 422 names the field; 409: reload)
 *   GET /api/transducers, PUT /api/transducers/{id}
 *   POST /api/capture/practice {setup, hits}         (GET /api/capture then shows "practice")
 *   GET /api/tests                                    (tests, their points, "next")
 * live.js asks DAQ.station.captureFields() for {setup, test, point} when it starts a capture.
 */
(function () {
  "use strict";

  const { api, el, $, fmt } = window.DAQ;

  const CHANNELS = ["hammer", "accelerometer"];
  const TOP_KEYS = ["span_hz", "lines", "center_hz", "averages", "trigger_source", "trigger_level_eu", "trigger_slope", "pre_trigger_s"];
  const CHANNEL_KEYS = ["transducer", "sensitivity_v_per_eu", "range_v", "window", "force_width_s", "exp_decay_s", "ac_coupled"];
  const NUMBER_KEYS = new Set([
    "span_hz", "center_hz", "trigger_level_eu", "pre_trigger_s",
    "sensitivity_v_per_eu", "force_width_s", "exp_decay_s",
  ]);
  const INTEGER_KEYS = new Set(["lines", "averages"]);
  const ALL_KEYS = [...TOP_KEYS, ...CHANNELS.flatMap((c) => CHANNEL_KEYS.map((k) => c + "." + k))];

  const st = {
    available: null, // null: not asked yet; false: the service has no /api/setups
    setups: [],
    loaded: null, // {name, version, setup, settings, cautions} in the editor
    transducers: [],
    practice: null,
    practiceWanted: 0,
    practicePoll: null,
    tests: [],
    testsAvailable: null,
  };

  /* ------------------------------------------------------------ helpers */

  /* The service's routes, from its OpenAPI description: a route it lacks is not asked for
   * (no 404 to clutter the console), its part of the page stays hidden. */
  let routes = null;
  async function hasRoute(path) {
    if (routes === null) {
      try {
        const r = await api("GET", "/openapi.json", null, { silent: true });
        routes = new Set(Object.keys((r && r.paths) || {}));
      } catch (e) {
        routes = undefined; // unknown: ask and see
      }
    }
    return routes === undefined || routes.has(path);
  }

  function form() {
    return $("setup-form");
  }

  function input(key) {
    return form().elements.namedItem(key);
  }

  function fieldOf(key) {
    return form().querySelector('[data-key="' + key + '"]');
  }

  /* "hammer.range_v: ..." or "range_v: ..." or "setup.hammer.range_v: ..." -> the form's key. */
  function keyOfDetail(detail, keys) {
    const head = String(detail).split(": ")[0].trim();
    const norm = head.replace(/^(setup|body)[.: ]/, "").replace(/[\[\]]/g, "").replace(/\s+/g, ".").replace(/:/g, ".");
    const sorted = [...keys].sort((a, b) => b.length - a.length);
    for (const k of sorted) if (norm === k || norm.endsWith("." + k)) return k;
    // "range_v" alone: the first channel's key it ends with, or a top key
    for (const k of sorted) if (k.endsWith("." + norm) || k === norm) return k;
    for (const k of sorted) if (norm.includes(k.split(".").pop()) && norm.includes(k.split(".")[0])) return k;
    return null;
  }

  function clearFieldErrors(root) {
    for (const f of root.querySelectorAll(".field.invalid, .check-field.invalid")) {
      f.classList.remove("invalid");
      const err = f.querySelector(".field-error");
      if (err) err.remove();
      const c = f.querySelector("input, select");
      if (c) {
        c.removeAttribute("aria-invalid");
        c.removeAttribute("aria-errormessage");
      }
    }
  }

  /* The service's one line, shown once. The setup form (columns of fields) shows it under
   * the field it names; the transducer form (a grid whose rows an extra line would
   * reflow) marks the field and shows the line under the form. The error line's data-for
   * names the field either way. */
  function showFieldError(root, keys, detail, lineId, inline) {
    clearFieldErrors(root);
    const key = keyOfDetail(detail, keys);
    const line = $(lineId);
    const field = key ? root.querySelector('[data-key="' + key + '"]') : null;
    line.dataset.for = field ? key : "";
    line.textContent = field && inline ? "" : detail;
    if (!field) return null;
    field.classList.add("invalid");
    if (inline) field.append(el("span", { class: "field-error", role: "alert", id: lineId + "-at-field" }, detail));
    const c = field.querySelector("input, select");
    if (c) {
      c.setAttribute("aria-invalid", "true");
      c.setAttribute("aria-errormessage", inline ? lineId + "-at-field" : lineId);
      c.focus();
    }
    return key;
  }

  function dataGet(data, key) {
    const [a, b] = key.split(".");
    if (b === undefined) return data ? data[a] : undefined;
    return data && data[a] && typeof data[a] === "object" ? data[a][b] : undefined;
  }

  function shown(v) {
    if (v === null || v === undefined) return "";
    if (typeof v === "number") return String(Number(v.toPrecision(10)));
    return String(v);
  }

  function overdue(t) {
    if (!t) return false;
    if (typeof t.overdue === "boolean") return t.overdue;
    if (!t.due) return false;
    return t.due < new Date().toISOString().slice(0, 10);
  }

  function transducerText(t) {
    const sens = fmt.sig(Number(t.sensitivity), 4) + " " + (t.sensitivity_unit || "");
    const due = t.due ? "calibration due " + t.due + (overdue(t) ? " (OVERDUE)" : "") : "no calibration date";
    return (t.model ? t.model + " · " : "") + sens + " · " + due;
  }

  /* ------------------------------------------------------------ setups */

  async function loadSetupList() {
    let r = null;
    try {
      if (await hasRoute("/api/setups")) r = await api("GET", "/api/setups", null, { quiet404: true, silent: true });
    } catch (e) {
      r = null;
    }
    if (!r || !Array.isArray(r.setups)) {
      st.available = false;
      $("setup-unavailable").hidden = false;
      $("capture-setup-field").hidden = true;
      return;
    }
    st.available = true;
    $("setup-unavailable").hidden = true;
    $("capture-setup-field").hidden = false;
    st.setups = r.setups;
    const names = r.setups.map((s) => s.name);
    const list = $("setup-list");
    const keep = list.value || (st.loaded && st.loaded.name) || "";
    list.replaceChildren(
      ...r.setups.map((s) =>
        el("option", { value: s.name }, s.name + (s.version !== undefined ? " (v" + s.version + ")" : ""))
      )
    );
    if (names.includes(keep)) list.value = keep;
    const cap = $("capture-setup");
    const keepCap = cap.value;
    cap.replaceChildren(
      el("option", { value: "" }, "the service's setup"),
      ...names.map((n) => el("option", { value: n }, n))
    );
    if (keepCap && names.includes(keepCap)) cap.value = keepCap;
    const newer = st.loaded && r.setups.find((x) => x.name === st.loaded.name);
    if (newer && Number.isFinite(newer.version) && Number.isFinite(st.loaded.version) && newer.version > st.loaded.version) {
      $("setup-status").textContent =
        "Version " + newer.version + " of " + newer.name + " was saved meanwhile (the editor holds version " +
        st.loaded.version + "): Load shows it.";
    }
    setupChoiceChanged();
  }

  /* live.js shows what the next capture uses ("Next capture: setup X vN"). */
  function setupChoiceChanged() {
    document.dispatchEvent(new Event("daq:setup-choice"));
  }

  function chosenSetup() {
    const name = st.available ? $("capture-setup").value : "";
    if (!name) return null;
    const listed = st.setups.find((x) => x.name === name);
    return { name, version: listed ? listed.version : undefined };
  }

  async function loadTransducers() {
    let r = null;
    try {
      if (await hasRoute("/api/transducers")) r = await api("GET", "/api/transducers", null, { quiet404: true, silent: true });
    } catch (e) {
      r = null;
    }
    st.transducers = r && Array.isArray(r.transducers) ? r.transducers : [];
    renderTransducers();
  }

  function renderTransducers() {
    const body = $("transducers-table").tBodies[0];
    body.replaceChildren(
      ...st.transducers.map((t) =>
        el(
          "tr",
          { dataset: { transducer: t.id }, class: overdue(t) ? "overdue-row" : null },
          el("td", null, t.id),
          el("td", null, t.kind || ""),
          el("td", null, t.model || ""),
          el("td", null, t.serial || ""),
          el("td", { class: "num" }, fmt.sig(Number(t.sensitivity), 4) + " " + (t.sensitivity_unit || "")),
          el("td", null, el("span", { class: "date" }, t.calibrated || "–")),
          el(
            "td",
            { class: overdue(t) ? "overdue" : null, title: overdue(t) ? "calibration overdue" : null },
            el("span", { class: "date" }, t.due || "–"),
            overdue(t) ? " overdue" : null
          ),
          el("td", null, el("button", { type: "button", class: "btn btn-small", dataset: { edit: t.id } }, "Edit"))
        )
      )
    );
    for (const c of CHANNELS) {
      const select = input(c + ".transducer");
      const keep = select.value;
      const kind = c === "hammer" ? "hammer" : "accelerometer";
      select.replaceChildren(
        el("option", { value: "" }, "none (sensitivity below)"),
        ...st.transducers
          .filter((t) => !t.kind || t.kind === kind)
          .map((t) => el("option", { value: t.id }, t.id + (overdue(t) ? " (calibration overdue)" : "")))
      );
      if ([...select.options].some((o) => o.value === keep)) select.value = keep;
      renderTransducerInfo(c);
    }
  }

  function renderTransducerInfo(channel) {
    const id = input(channel + ".transducer").value;
    const info = form().querySelector('[data-info-for="' + channel + '"]');
    const t = st.transducers.find((x) => x.id === id);
    info.textContent = t ? transducerText(t) : "";
    info.classList.toggle("overdue", Boolean(t && overdue(t)));
    const sens = input(channel + ".sensitivity_v_per_eu");
    sens.disabled = Boolean(t);
    if (t && Number.isFinite(t.sensitivity_v_per_eu)) sens.value = fmt.sig(t.sensitivity_v_per_eu, 6);
  }

  /* The form from a setup: the file's values in the fields, the resolved ones as placeholders. */
  function fillForm(setup, settings) {
    clearFieldErrors(form());
    $("setup-error").textContent = "";
    for (const key of ALL_KEYS) {
      const c = input(key);
      if (!c) continue;
      const v = dataGet(setup, key);
      const resolved = dataGet(settings, key);
      if (c.type === "checkbox") {
        c.checked = Boolean(v !== undefined ? v : resolved);
      } else if (c.tagName === "SELECT") {
        const want = v === undefined || v === null ? "" : String(v);
        c.value = [...c.options].some((o) => o.value === want) ? want : "";
      } else {
        c.value = v === undefined ? "" : v === null ? (key.endsWith("range_v") ? "auto" : "") : shown(v);
        c.placeholder = resolved === null ? (key.endsWith("range_v") ? "auto" : "") : shown(resolved);
      }
    }
    for (const ch of CHANNELS) renderTransducerInfo(ch);
  }

  /* The setup dict from the form: empty fields left out (they keep the defaults). */
  function readForm() {
    const out = {};
    const put = (key, v) => {
      const [a, b] = key.split(".");
      if (b === undefined) out[a] = v;
      else (out[a] = out[a] || {})[b] = v;
    };
    for (const key of ALL_KEYS) {
      const c = input(key);
      if (!c) continue;
      const leaf = key.split(".").pop();
      if (c.type === "checkbox") {
        put(key, c.checked);
        continue;
      }
      if (c.disabled) continue; // the sensitivity of a named transducer
      const raw = c.value.trim();
      if (raw === "") continue;
      if (leaf === "range_v" && raw.toLowerCase() === "auto") put(key, "auto");
      else if (NUMBER_KEYS.has(leaf) || leaf === "range_v") put(key, Number.isFinite(Number(raw)) ? Number(raw) : raw);
      else if (INTEGER_KEYS.has(leaf)) put(key, Number.isInteger(Number(raw)) ? Number(raw) : raw);
      else put(key, raw);
    }
    return out;
  }

  function renderLoaded() {
    const l = st.loaded;
    $("setup-version").textContent = l ? l.name + (l.version !== undefined ? " · version " + l.version : "") + (l.saved_utc ? " · saved " + fmt.time(l.saved_utc) : "") : "";
    $("setup-cautions").replaceChildren(...DAQ.cautionLines(l && l.cautions));
  }

  async function loadSetup(name) {
    if (!name) return;
    let r;
    try {
      r = await api("GET", "/api/setups/" + encodeURIComponent(name), null, { quiet404: true });
    } catch (e) {
      return;
    }
    if (!r) {
      DAQ.showError("no setup '" + name + "' (reload the list)");
      return;
    }
    st.loaded = r;
    $("setup-name").value = r.name;
    $("setup-status").textContent = "";
    fillForm(r.setup || {}, r.settings || {});
    renderLoaded();
    await loadSetupList(); // the list's versions, as the header's (someone may have saved meanwhile)
    $("setup-list").value = r.name;
  }

  async function saveSetup() {
    const name = $("setup-name").value.trim();
    clearFieldErrors(form());
    $("setup-error").textContent = "";
    $("setup-status").textContent = "";
    if (!/^[A-Za-z0-9._-]{1,64}$/.test(name)) {
      $("setup-error").textContent = "name: letters, digits, '.', '_' or '-' (at most 64)";
      $("setup-name").focus();
      return;
    }
    const same = st.loaded && st.loaded.name === name;
    const listed = st.setups.find((s) => s.name === name);
    const version = same ? st.loaded.version : listed ? listed.version : 0;
    let r;
    try {
      r = await api("PUT", "/api/setups/" + encodeURIComponent(name), { setup: readForm(), version }, { silent: true });
    } catch (e) {
      if (e.status === 422) showFieldError(form(), ALL_KEYS, e.message, "setup-error", true);
      else if (e.status === 409) {
        $("setup-error").textContent = e.message + " — someone saved this setup meanwhile: load it again, then make your changes.";
      } else $("setup-error").textContent = e.message;
      return;
    }
    st.loaded = r;
    fillForm(r.setup || {}, r.settings || {});
    renderLoaded();
    $("setup-status").textContent = "Saved " + r.name + " version " + r.version + ".";
    await loadSetupList();
    $("setup-list").value = r.name;
  }

  function useForCapture() {
    const name = (st.loaded && st.loaded.name) || $("setup-list").value;
    if (!name) return;
    $("capture-setup").value = name;
    renderCaptureSetupNote();
    setupChoiceChanged();
    $("setup-status").textContent = "The next capture starts with setup " + name + ".";
  }

  async function renderCaptureSetupNote() {
    const name = $("capture-setup").value;
    const list = $("station-cautions");
    if (document.body.dataset.captureState === "running") return; // the capture's own show then
    if (!name) {
      list.replaceChildren();
      return;
    }
    let r = null;
    try {
      r = await api("GET", "/api/setups/" + encodeURIComponent(name), null, { quiet404: true, silent: true });
    } catch (e) {
      r = null;
    }
    if (r && $("capture-setup").value === name) list.replaceChildren(...DAQ.cautionLines(r.cautions));
  }

  /* ------------------------------------------------------------ transducer form */

  const TRANSDUCER_KEYS = ["id", "kind", "model", "serial", "sensitivity", "sensitivity_unit", "calibrated", "due"];

  function editTransducer(id) {
    const t = st.transducers.find((x) => x.id === id);
    if (!t) return;
    const f = $("transducer-form");
    for (const k of TRANSDUCER_KEYS) {
      const c = f.elements.namedItem(k);
      if (c) c.value = t[k] === undefined || t[k] === null ? "" : String(t[k]);
    }
    f.elements.namedItem("model").focus();
  }

  async function saveTransducer(e) {
    e.preventDefault();
    const f = $("transducer-form");
    clearFieldErrors(f);
    $("transducer-error").textContent = "";
    const body = {};
    for (const k of TRANSDUCER_KEYS) {
      const v = f.elements.namedItem(k).value.trim();
      body[k] = k === "sensitivity" ? (Number.isFinite(Number(v)) && v !== "" ? Number(v) : v) : v;
    }
    if (!body.id) {
      showFieldError(f, TRANSDUCER_KEYS, "id: give the transducer a name", "transducer-error", false);
      return;
    }
    try {
      await api("PUT", "/api/transducers/" + encodeURIComponent(body.id), body, { silent: true });
    } catch (err) {
      if (err.status === 422) showFieldError(f, TRANSDUCER_KEYS, err.message, "transducer-error", false);
      else $("transducer-error").textContent = err.message;
      return;
    }
    $("setup-status").textContent = "Saved transducer " + body.id + ".";
    await loadTransducers();
  }

  /* ------------------------------------------------------------ practice hits */

  async function startPractice() {
    const name = (st.loaded && st.loaded.name) || $("setup-list").value || undefined;
    const hits = Number($("practice-hits").value) || 3;
    $("practice-apply").hidden = true;
    $("practice-result").textContent = "Hit the structure " + fmt.plural(hits, "time", "times") + " as you will in the test…";
    st.practice = null;
    st.practiceWanted = hits;
    try {
      if (!(await hasRoute("/api/capture/practice"))) throw new DAQ.ApiError("no route", 404, null);
      await api("POST", "/api/capture/practice", name ? { setup: name, hits } : { hits }, { silent: true });
    } catch (e) {
      if (e.status === 422 && name && keyOfDetail(e.message, ALL_KEYS)) {
        // the setup asks what the analyzer cannot do: said beside the field, as on save
        showFieldError(form(), ALL_KEYS, e.message, "setup-error", true);
        $("practice-result").textContent = "Practice hits: the setup needs a change first (" + e.message + ").";
        return;
      }
      $("practice-result").textContent =
        e.status === 404 || e.status === 405 ? "This service cannot take practice hits yet." : "Practice hits: " + e.message;
      return;
    }
    clearInterval(st.practicePoll);
    st.practicePoll = setInterval(pollPractice, 700);
  }

  async function pollPractice() {
    let s;
    try {
      s = await api("GET", "/api/capture", null, { silent: true });
    } catch (e) {
      return;
    }
    const p = s && s.practice;
    if (p && typeof p === "object") showPractice(p, s.state);
    const over = p && (p.state === "done" || p.state === "failed" || p.done || p.error);
    const done = over || (p && s.state === "idle" && p.state === undefined && p.hits_taken !== undefined);
    if (done || (s && s.state === "idle" && !p)) {
      clearInterval(st.practicePoll);
      st.practicePoll = null;
    }
  }

  function showPractice(p, state) {
    st.practice = p;
    const parts = [];
    parts.push(fmt.plural(p.hits_taken || 0, "practice hit", "practice hits"));
    if (Array.isArray(p.peaks_force_n) && p.peaks_force_n.length) {
      parts.push("peaks " + p.peaks_force_n.map((v) => fmt.sig(v, 3)).join(", ") + " N");
    }
    if (Array.isArray(p.peaks_response_m_s2) && p.peaks_response_m_s2.length) {
      parts.push("response " + p.peaks_response_m_s2.map((v) => fmt.sig(v, 3)).join(", ") + " m/s²");
    }
    const proposed = [];
    if (Number.isFinite(p.hammer_range_v)) proposed.push("hammer range " + fmt.sig(p.hammer_range_v, 3) + " V");
    if (Number.isFinite(p.accelerometer_range_v)) proposed.push("accelerometer range " + fmt.sig(p.accelerometer_range_v, 3) + " V");
    if (Number.isFinite(p.trigger_level_eu)) proposed.push("trigger level " + fmt.sig(p.trigger_level_eu, 3) + " N");
    let text = parts.join(" · ");
    if (proposed.length) text += ". Proposed: " + proposed.join(", ") + ".";
    if (p.state === "failed" || p.error) text += " Failed: " + (p.error || p.message || "no reason given");
    $("practice-result").textContent = text;
    const finished = p.state ? p.state === "done" : !state || state === "idle";
    $("practice-apply").hidden = !proposed.length || !finished;
  }

  async function applyPractice() {
    const p = st.practice;
    if (!p) return;
    if (Number.isFinite(p.hammer_range_v)) input("hammer.range_v").value = String(p.hammer_range_v);
    if (Number.isFinite(p.accelerometer_range_v)) input("accelerometer.range_v").value = String(p.accelerometer_range_v);
    if (Number.isFinite(p.trigger_level_eu)) input("trigger_level_eu").value = String(Number(p.trigger_level_eu.toPrecision(3)));
    await saveSetup();
  }

  /* ------------------------------------------------------------ tests, points */

  async function loadTests() {
    let r = null;
    try {
      if (await hasRoute("/api/tests")) r = await api("GET", "/api/tests", null, { quiet404: true, silent: true });
    } catch (e) {
      r = null;
    }
    st.testsAvailable = Boolean(r && Array.isArray(r.tests));
    st.tests = st.testsAvailable ? r.tests : [];
    $("capture-test-field").hidden = !st.testsAvailable || !st.tests.length;
    $("capture-point-field").hidden = !st.testsAvailable || !st.tests.length;
    const select = $("capture-test");
    const keep = select.value;
    select.replaceChildren(
      el("option", { value: "" }, "none"),
      ...st.tests.map((t) => el("option", { value: t.name }, t.name))
    );
    if (st.tests.some((t) => t.name === keep)) select.value = keep;
    renderPoints();
  }

  function pointLabel(p) {
    const where = Number.isFinite(p.position_m) ? " (x = " + fmt.sig(p.position_m, 4) + " m)" : p.node !== undefined && p.node !== null ? " (node " + p.node + ")" : "";
    const runs = Array.isArray(p.runs) && p.runs.length ? ", " + fmt.plural(p.runs.length, "run", "runs") : "";
    return (p.measured ? "✓ " : "") + p.name + where + (p.measured ? " measured" + runs : "");
  }

  function renderPoints() {
    const t = st.tests.find((x) => x.name === $("capture-test").value);
    const select = $("capture-point");
    const keep = select.value;
    if (!t) {
      select.replaceChildren(el("option", { value: "" }, "–"));
      select.disabled = true;
      return;
    }
    const points = Array.isArray(t.points) ? t.points : [];
    select.replaceChildren(
      ...(t.next ? [el("option", { value: "next" }, "next: " + t.next)] : []),
      ...points.map((p) => el("option", { value: p.name, class: p.measured ? "measured" : null }, pointLabel(p)))
    );
    select.disabled = false;
    if ([...select.options].some((o) => o.value === keep)) select.value = keep;
    else select.value = t.next ? "next" : points.length ? points[0].name : "";
  }

  /* ------------------------------------------------------------ wiring */

  function openEditor(open) {
    const ed = $("setup-editor");
    ed.hidden = !open;
    $("setup-toggle").setAttribute("aria-expanded", open ? "true" : "false");
    if (open) {
      refresh().then(() => {
        if (!st.loaded && st.available) loadSetup($("capture-setup").value || $("setup-list").value || "default");
      });
    }
  }

  async function refresh() {
    await Promise.allSettled([loadSetupList(), loadTransducers(), loadTests()]);
  }

  $("setup-toggle").addEventListener("click", () => openEditor($("setup-editor").hidden));
  $("setup-close").addEventListener("click", () => openEditor(false));
  $("setup-load").addEventListener("click", () => loadSetup($("setup-list").value));
  $("setup-save").addEventListener("click", () => saveSetup());
  $("setup-use").addEventListener("click", () => useForCapture());
  $("setup-form").addEventListener("submit", (e) => {
    e.preventDefault();
    saveSetup();
  });
  for (const c of CHANNELS) {
    input(c + ".transducer").addEventListener("change", () => renderTransducerInfo(c));
  }
  $("transducer-form").addEventListener("submit", saveTransducer);
  $("transducers-table").tBodies[0].addEventListener("click", (e) => {
    const b = e.target.closest("button[data-edit]");
    if (b) editTransducer(b.dataset.edit);
  });
  $("practice-start").addEventListener("click", () => startPractice());
  $("practice-apply").addEventListener("click", () => applyPractice());
  $("capture-test").addEventListener("change", renderPoints);
  $("capture-setup").addEventListener("change", () => {
    renderCaptureSetupNote();
    setupChoiceChanged();
  });
  // back to the page (another tab or a colleague may have saved a setup): the list anew
  window.addEventListener("focus", () => {
    if (st.available) loadSetupList();
  });
  document.addEventListener("visibilitychange", () => {
    if (document.visibilityState === "visible" && st.available) loadSetupList();
  });

  // a run sealed: the test's points may have a new measured one
  for (const type of ["run_sealed", "capture_ended"]) {
    DAQ.events.on(type, () => {
      if (st.testsAvailable) loadTests();
    });
  }
  DAQ.events.onHello(() => refresh());

  DAQ.station = {
    /* what a capture starts with: only what was chosen (the service's own setup otherwise) */
    captureFields() {
      const out = {};
      const setup = $("capture-setup").value;
      if (setup && st.available) out.setup = setup;
      const test = $("capture-test").value;
      if (test && st.testsAvailable) {
        out.test = test;
        const point = $("capture-point").value;
        if (point) out.point = point;
      }
      return out;
    },
    refresh,
    chosenSetup,
    openEditor,
    loadSetup,
  };

  if (new URLSearchParams(window.location.search).get("setup") !== null) openEditor(true);
})();
