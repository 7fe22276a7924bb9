/* The live capture page (index.html) of `daq serve`.
 *
 * State comes from GET /api/capture (on load, on every (re)connection of the
 * event stream, after each action) and is kept current by the SSE events.
 * Events that arrive while a snapshot is being fetched are held back and
 * applied after it, so a late snapshot never overwrites a newer event.
 */
(function () {
  "use strict";

  const { api, el, $, fmt, events } = window.DAQ;

  /* ------------------------------------------------------------------ state */

  const cap = {
    state: null, // "idle" | "running" | "stopping", null before the first snapshot
    run_id: null,
    hits_wanted: 0,
    accepted: 0,
    auto: false,
    pending: null,
    hits: new Map(), // index -> hit summary
    settings: null,
    last_run_id: null,
    last_outcome: null,
    last_error: null,
    ended_run_id: null, // the capture the outcome is about, when we know it
    undo_window_s: null, // how long the service holds a decision before the analyzer gets it
    setup: null, // {name, version} of the capture's setup (the last one's when idle)
    next_setup: undefined, // {name, version} | null of the service's own setup; undefined: not said
    transducers: null,
    cautions: [],
  };

  /* The last decision and until when (performance.now() ms) it can be undone. */
  const undo = { index: null, accepted: null, until: 0, busy: false, supported: true, timer: null };

  /* ----------------------------------------------------------------- sound */

  /* Short tones made with WebAudio (no audio files): a beep per hit, a rising pair on
   * accept, a low buzz on reject, a falling pair on undo. Off by default; the choice is
   * kept in localStorage. Browsers let a page sound only after a click or a key. */
  const SOUND_KEY = "daq-sound";
  const soundedDecision = new Set(); // "<run>:<index>:<accepted>" already sounded
  const sound = (function () {
    let on = false;
    let ctx = null;
    try {
      on = localStorage.getItem(SOUND_KEY) === "on";
    } catch (e) {
      on = false;
    }

    function context() {
      if (!ctx) {
        const AC = window.AudioContext || window.webkitAudioContext;
        if (!AC) return null;
        ctx = new AC();
      }
      if (ctx.state === "suspended") ctx.resume().catch(() => {});
      return ctx;
    }

    function tone(freq, startS, durS, type) {
      const c = context();
      if (!c) return;
      const t0 = c.currentTime + startS;
      const osc = c.createOscillator();
      const gain = c.createGain();
      osc.type = type || "sine";
      osc.frequency.value = freq;
      gain.gain.setValueAtTime(0.0001, t0);
      gain.gain.exponentialRampToValueAtTime(0.25, t0 + 0.01);
      gain.gain.exponentialRampToValueAtTime(0.0001, t0 + durS);
      osc.connect(gain).connect(c.destination);
      osc.start(t0);
      osc.stop(t0 + durS + 0.02);
    }

    function play(fn, name) {
      document.body.dataset.lastSound = name; // for tests and the curious
      if (!on) return;
      try {
        fn();
      } catch (e) {
        /* no sound, no harm */
      }
    }

    function render() {
      const b = $("sound-toggle");
      b.textContent = "Sound: " + (on ? "on" : "off");
      b.setAttribute("aria-pressed", on ? "true" : "false");
    }

    return {
      hit: () => play(() => tone(1200, 0, 0.08), "hit"),
      accept: () => play(() => { tone(660, 0, 0.1); tone(990, 0.11, 0.14); }, "accept"),
      reject: () => play(() => tone(180, 0, 0.3, "square"), "reject"),
      undo: () => play(() => { tone(880, 0, 0.08); tone(520, 0.09, 0.12); }, "undo"),
      toggle() {
        on = !on;
        try {
          localStorage.setItem(SOUND_KEY, on ? "on" : "off");
        } catch (e) {
          /* for this page only */
        }
        if (on) context(); // made inside the click: browsers allow it then
        render();
        if (on) tone(990, 0, 0.08);
      },
      wake() {
        if (on) context();
      },
      render,
      get on() {
        return on;
      },
    };
  })();

  let instrument = {};
  let instrumentReq = 0;
  let shownHitKey = null; // "<run_id>:<index>" of the traces on the plots
  let tracesReq = 0;
  let shownFrfKey = null; // "<run_id>:<n_averaged>"
  let frfReq = 0;
  let deciding = false;
  let starting = false;

  const results = {
    runId: null,
    analysis: null,
    fits: null,
    analysisState: null,
    analysisError: null,
    fitState: null,
    fitError: null,
    preferredFit: null,
  };
  const resultsReq = { states: 0, analysis: 0, fits: 0 };

  /* ------------------------------------------------------------------ plots */

  const WINDOW_STROKE = "#6b7280";
  const plots = {
    force: DAQ.plot($("force-plot"), {
      xLabel: "Time (ms)",
      yLabel: "Force (N)",
      series: [
        { label: "Force (N)", stroke: "#1d4ed8" },
        { label: "force window", stroke: WINDOW_STROKE, dash: [6, 4], width: 1 },
      ],
      group: "traces",
      emptyText: "no hit yet",
    }),
    response: DAQ.plot($("response-plot"), {
      xLabel: "Time (ms)",
      yLabel: "Response (m/s²)",
      series: [
        { label: "Response (m/s²)", stroke: "#c2410c" },
        { label: "exponential window", stroke: WINDOW_STROKE, dash: [6, 4], width: 1 },
      ],
      group: "traces",
      emptyText: "no hit yet",
    }),
    pulse: DAQ.plot($("pulse-plot"), {
      xLabel: "Time (ms)",
      yLabel: "Force (N)",
      series: [{ label: "Force (N)", stroke: "#1d4ed8" }],
      height: 170,
      emptyText: "no hit yet",
    }),
    spectrum: DAQ.plot($("spectrum-plot"), {
      xLabel: "Frequency (Hz)",
      yLabel: "Force (dB)",
      series: [
        { label: "force (dB)", stroke: "#1d4ed8" },
        { label: "roll-off limit (dB)", stroke: "#b91c1c", dash: [6, 4], width: 1.5 },
      ],
      height: 170,
      group: "quality",
      emptyText: "no hit yet",
    }),
    hitFrf: DAQ.plot($("hit-frf-plot"), {
      xLabel: "Frequency (Hz)",
      yLabel: "|H| ((m/s²)/N)",
      series: [
        { label: "average", stroke: "#1d4ed8", width: 2.5 },
        { label: "this hit", stroke: "#c2410c", width: 1.25 },
      ],
      logY: true,
      height: 170,
      group: "quality",
      emptyText: "no hit yet",
    }),
    hitPhase: DAQ.plot($("hit-phase-plot"), {
      xLabel: "Frequency (Hz)",
      yLabel: "Phase (°)",
      series: [
        { label: "average", stroke: "#1d4ed8", width: 2.5 },
        { label: "this hit", stroke: "#c2410c", width: 1.25 },
      ],
      yRange: [-180, 180],
      ySplits: [-180, -90, 0, 90, 180],
      height: 170,
      group: "quality",
      emptyText: "no hit yet",
    }),
    hitCoherence: DAQ.plot($("hit-coherence-plot"), {
      xLabel: "Frequency (Hz)",
      yLabel: "Coherence",
      series: [{ label: "coherence", stroke: "#15803d" }],
      yRange: [0, 1],
      height: 170,
      group: "quality",
      emptyText: "no accepted hit yet",
    }),
    frf: DAQ.plot($("frf-plot"), {
      xLabel: "Frequency (Hz)",
      yLabel: "|H| ((m/s²)/N)",
      series: [{ label: "|H| ((m/s²)/N)", stroke: "#1d4ed8" }],
      logY: true,
      group: "frf",
      keepZoom: true,
      emptyText: "no accepted hit yet",
    }),
    coherence: DAQ.plot($("coherence-plot"), {
      xLabel: "Frequency (Hz)",
      yLabel: "Coherence",
      series: [{ label: "Coherence", stroke: "#15803d" }],
      yRange: [0, 1],
      group: "frf",
      keepZoom: true,
      emptyText: "no accepted hit yet",
    }),
  };

  /* --------------------------------------------------------------- helpers */

  /* People count hits from 1: the API's "number", else its 0-based index + 1. */
  function hitNumber(h) {
    if (h && Number.isInteger(h.number)) return h.number;
    return h && Number.isInteger(h.index) ? h.index + 1 : null;
  }

  function numberOf(index) {
    const h = cap.hits.get(index);
    return h ? hitNumber(h) : index + 1;
  }

  /* accepted although a check failed */
  function againstChecks(h) {
    if (typeof h.accepted_against_checks === "boolean") return h.accepted_against_checks;
    return Boolean(h.decided && h.accepted && h.passed === false);
  }

  function latestIndex() {
    let best = null;
    for (const i of cap.hits.keys()) if (best === null || i > best) best = i;
    return best;
  }

  /* A held decision (undo_window_s before the analyzer gets it) reads as made; the row
   * says "held" beside it (CSS, not in the text). */
  function verdictText(h) {
    if (!h.decided && h.held) {
      if (h.heldAccepted === true) return "accepted";
      if (h.heldAccepted === false) return h.reason ? "rejected: " + h.reason : "rejected";
      return "held";
    }
    if (!h.decided) return "pending";
    if (h.accepted) return "accepted";
    return h.reason ? "rejected: " + h.reason : "rejected";
  }

  function checksText(h) {
    let text = h.passed ? "pass" : "fail" + (h.suggested_reason ? ": " + h.suggested_reason : "");
    const ov = Array.isArray(h.overload) ? h.overload : [];
    const which = [];
    if (ov[0]) which.push("force");
    if (ov[1]) which.push("response");
    if (which.length) text += " · overload " + which.join(", ");
    return text;
  }

  /* a hit summary from a `hit` event */
  function summaryFromEvent(ev) {
    return {
      index: ev.index,
      number: ev.number,
      decided: false,
      accepted: null,
      reason: "",
      peak_force_n: ev.peak_force_n,
      overload: ev.overload,
      timestamp_utc: ev.timestamp_utc,
      passed: ev.passed,
      suggested_reason: ev.suggested_reason || "",
      checks: ev.checks || [],
    };
  }

  /* --------------------------------------------------------------- render */

  function renderState() {
    const box = $("capture-state");
    const st = cap.state;
    box.textContent = st === null ? "unknown" : st;
    box.className = "state state-" + (st || "unknown");
    $("start").disabled = st !== "idle" || starting;
    $("stop").disabled = st !== "running";
    $("abort").disabled = st !== "running";
    document.body.dataset.captureState = st || "unknown";
    renderProgress();
    renderUndo();
  }

  function renderProgress() {
    $("large-accepted").textContent = String(cap.accepted || 0);
    $("large-wanted").textContent = String(cap.hits_wanted || 0);
    $("large-taken").textContent = cap.run_id ? fmt.plural(cap.hits.size, "hit", "hits") + " taken" : "";
    const box = $("capture-progress");
    if (!cap.run_id) {
      box.textContent = cap.state === "idle" ? "No capture yet." : "";
      return;
    }
    const taken = cap.hits.size;
    const mode = cap.auto ? "the checks decide" : "you decide each hit";
    const counts =
      cap.accepted + " of " + cap.hits_wanted + " accepted, " + fmt.plural(taken, "hit", "hits") + " taken";
    if (cap.state === "running" || cap.state === "stopping") {
      box.textContent = "Run " + cap.run_id + ": " + counts + " (" + mode + ").";
    } else {
      box.textContent = "Last capture " + cap.run_id + ": " + counts + ".";
    }
  }

  function renderSettings() {
    const box = $("capture-settings");
    const s = cap.settings;
    if (!s || typeof s !== "object") {
      box.textContent = "";
      return;
    }
    const parts = [];
    const known = { span_hz: ["span", "Hz"], record_length_s: ["record", "s"] };
    for (const [k, [label, unit]] of Object.entries(known)) {
      if (typeof s[k] === "number") parts.push(label + " " + fmt.sig(s[k], 5) + " " + unit);
    }
    for (const [k, v] of Object.entries(s)) {
      if (k in known || parts.length >= 10) continue;
      if (typeof v === "number") parts.push(k + " " + fmt.sig(v, 5));
      else if (typeof v === "string" || typeof v === "boolean") parts.push(k + " " + v);
    }
    box.textContent = parts.length ? "Analyzer settings: " + parts.join(" · ") : "";
  }

  function setupText(setup) {
    if (!setup || !setup.name) return null;
    const v = setup.version;
    return "setup " + setup.name + (v !== undefined && v !== null ? " v" + v : "");
  }

  /* The setup the next Start uses: the one chosen in the capture form (its version from the
   * setup list), else the service's own (the snapshot's next_setup, where the service says),
   * else just "the service's setup". */
  function nextSetupText() {
    const chosen = DAQ.station && DAQ.station.chosenSetup ? DAQ.station.chosenSetup() : null;
    if (chosen && chosen.name) return setupText(chosen);
    if (cap.next_setup !== undefined) {
      return setupText(cap.next_setup) || "the service's own settings (no named setup)";
    }
    return "the service's setup";
  }

  /* The capture's setup and transducers, and its cautions (an overdue calibration) in view:
   * "This capture: ..." while one runs; when idle, "Next capture: ..." (what Start uses)
   * and "Last capture: ..." (what the last one used), each on its own line. */
  function renderSetupLine() {
    const box = $("capture-setup-note");
    const parts = [];
    const used = setupText(cap.setup);
    if (used) parts.push(used);
    const tr = cap.transducers || {};
    for (const ch of ["hammer", "accelerometer"]) {
      const t = tr[ch];
      if (t && typeof t === "object") parts.push(ch + " " + (t.id || t.model || "?"));
    }
    const running = cap.state === "running" || cap.state === "stopping";
    const lines = [];
    if (running) {
      if (cap.run_id && parts.length) lines.push(["this", "This capture: " + parts.join(" · ")]);
    } else {
      if (cap.state !== null) lines.push(["next", "Next capture: " + nextSetupText()]);
      if (cap.run_id && parts.length) lines.push(["last", "Last capture: " + parts.join(" · ")]);
    }
    box.replaceChildren(
      ...lines.map(([kind, text]) => el("span", { class: "setup-line", dataset: { setupLine: kind } }, text))
    );
    $("station-cautions").replaceChildren(...DAQ.cautionLines(cap.cautions));
  }

  // the station part (station.js) says when the setup chosen for the next capture changed
  document.addEventListener("daq:setup-choice", renderSetupLine);

  function renderInstrument() {
    const box = $("instrument-status");
    const i = instrument;
    box.textContent = "";
    if (!i || (i.resource === undefined && i.connected === undefined)) {
      box.textContent = "…";
      return;
    }
    box.className = "instrument " + (i.connected ? "connected" : "disconnected");
    const resource = (i.resource || "analyzer") + (i.simulated ? " (simulated)" : "");
    box.append(
      el("span", { class: "dot", "aria-hidden": "true" }),
      el("span", { class: "resource" }, resource),
      " · ",
      el("span", { class: "link-state" }, i.connected ? "connected" : "not connected")
    );
    if (i.identification) box.append(" · ", el("span", { class: "ident" }, i.identification));
    if (i.dialect) box.append(" · ", el("span", { class: "dialect" }, i.dialect + " dialect"));
    if (i.last_error) box.append(" · ", el("span", { class: "last-error" }, i.last_error));
    box.title = [resource, i.connected ? "connected" : "not connected", i.identification, i.detection, i.last_error]
      .filter(Boolean)
      .join("\n");
  }

  function hitRow(h) {
    const verdict = verdictText(h);
    const state =
      !h.decided && h.held
        ? "held row-" + (h.heldAccepted === false ? "rejected" : "accepted")
        : !h.decided
          ? "pending"
          : h.accepted
            ? "accepted"
            : "rejected";
    const tr = el(
      "tr",
      {
        dataset: { index: String(h.index) },
        class: "hit-row row-" + state + (shownHitKey === cap.run_id + ":" + h.index ? " shown" : ""),
        title: h.timestamp_utc ? "taken " + fmt.time(h.timestamp_utc) + " (click to see its traces)" : null,
      },
      el(
        "td",
        { class: "num hit-number" },
        againstChecks(h)
          ? el(
              "span",
              {
                class: "against-mark",
                role: "img",
                "aria-label": "accepted against a failed check",
                title:
                  "accepted although the checks failed" +
                  (h.suggested_reason ? ": " + h.suggested_reason : "") +
                  "; the report marks it too",
              },
              "⚠"
            )
          : null,
        String(hitNumber(h))
      ),
      el("td", { class: "num" }, fmt.fixed(h.peak_force_n, 2)),
      el(
        "td",
        {
          class: "checks-cell " + (h.passed ? "pass" : "fail"),
          title: (h.checks || []).map((c) => (c.passed ? "✓ " : "✗ ") + c.name + ": " + c.detail).join("\n") || null,
        },
        checksText(h)
      ),
      el("td", { class: "verdict", title: h.held && !h.decided ? "held: Undo [U] takes it back until the analyzer gets it" : null }, verdict)
    );
    if (againstChecks(h)) tr.classList.add("against-checks");
    return tr;
  }

  function renderHitsTable() {
    const body = $("hits-table").tBodies[0];
    const rows = [...cap.hits.values()].sort((a, b) => a.index - b.index).map(hitRow);
    body.replaceChildren(...rows);
    scrollHitsToEnd();
  }

  function upsertHitRow(h) {
    const body = $("hits-table").tBodies[0];
    const row = hitRow(h);
    const old = body.querySelector('tr[data-index="' + h.index + '"]');
    if (old) {
      old.replaceWith(row);
      return;
    }
    // keep the rows in hit order
    const after = [...body.rows].find((r) => Number(r.dataset.index) > h.index);
    body.insertBefore(row, after || null);
    scrollHitsToEnd();
  }

  function scrollHitsToEnd() {
    const wrap = $("hits-table").parentElement;
    wrap.scrollTop = wrap.scrollHeight;
  }

  function markShownRow() {
    for (const r of $("hits-table").tBodies[0].rows) {
      r.classList.toggle("shown", shownHitKey === cap.run_id + ":" + r.dataset.index);
    }
  }

  let lastPendingShown = null;

  function renderPending() {
    const idx = cap.pending;
    const h = idx !== null && idx !== undefined ? cap.hits.get(idx) : null;
    const panel = $("pending");
    const waiting = idx !== null && idx !== undefined;
    panel.classList.toggle("waiting", waiting);
    if (waiting) $("pending-index").textContent = "Hit " + numberOf(idx);
    else if (cap.auto && cap.state === "running") $("pending-index").textContent = "none (the checks decide)";
    else $("pending-index").textContent = "none";

    const list = $("checks");
    list.replaceChildren(
      ...(h && h.checks ? h.checks : []).map((c) =>
        el(
          "li",
          { class: c.passed ? "pass" : "fail" },
          el("span", { class: "check-mark", "aria-hidden": "true" }, c.passed ? "✓" : "✗"),
          el("span", { class: "check-name" }, c.name),
          c.detail ? el("span", { class: "check-detail" }, c.detail) : null
        )
      )
    );

    const sug = $("suggested");
    if (h) {
      sug.textContent = h.passed
        ? "The checks suggest: accept"
        : "The checks suggest: reject" + (h.suggested_reason ? " (" + h.suggested_reason + ")" : "");
      sug.className = "suggested " + (h.passed ? "pass" : "fail");
    } else {
      sug.textContent = waiting ? "" : "No hit is waiting for a decision.";
      sug.className = "suggested muted";
    }
    sug.title = sug.textContent; // all of it where the large display cuts it to one line

    const reason = $("reject-reason");
    if (idx !== lastPendingShown) {
      reason.value = "";
      lastPendingShown = idx;
    }
    reason.placeholder = h && !h.passed && h.suggested_reason ? h.suggested_reason : "";
    $("accept").disabled = !waiting || deciding;
    $("reject").disabled = !waiting || deciding;
    document.body.classList.toggle("hit-waiting", waiting);
    renderUndo();
  }

  /* ------------------------------------------------------------------ undo */

  function undoLeftS() {
    return Math.max(0, (undo.until - performance.now()) / 1000);
  }

  function renderUndo() {
    const button = $("undo");
    const note = $("undo-note");
    const live = cap.state === "running" && undo.index !== null && undoLeftS() > 0;
    button.disabled = !undo.supported || !live || undo.busy || deciding;
    if (!undo.supported) note.textContent = "";
    else if (live) {
      note.textContent =
        "Hit " + numberOf(undo.index) + " " + (undo.accepted === true ? "accepted" : undo.accepted === false ? "rejected" : "decided") +
        ": held " + Math.ceil(undoLeftS()) + " s more before the analyzer gets it (Undo [U] takes it back).";
    } else note.textContent = "";
    if (live && !undo.timer) {
      undo.timer = setInterval(() => {
        if (undoLeftS() <= 0) {
          clearInterval(undo.timer);
          undo.timer = null;
        }
        renderUndo();
      }, 250);
    }
  }

  /* A decision was made (here, or seen in a snapshot that holds one). */
  function noteDecision(index, accepted, heldS) {
    const s = typeof heldS === "number" && Number.isFinite(heldS) ? heldS : cap.undo_window_s;
    undo.index = index;
    undo.accepted = accepted;
    // the service did not say: let the page offer undo for 3 s (its default); a late one gets 409
    undo.until = performance.now() + 1000 * (typeof s === "number" ? s : 3);
    renderUndo();
  }

  /* A refused undo ("hit 1 is already in the analyzer's average") is news of the moment:
   * it goes when the next hit arrives, or after a few seconds, not over the next hit. */
  const REFUSAL_SHOWN_MS = 5000;
  let refusal = { text: null, timer: null };

  function clearRefusal() {
    clearTimeout(refusal.timer);
    if (refusal.text !== null && $("error").textContent === refusal.text) DAQ.clearError();
    refusal = { text: null, timer: null };
  }

  function noteRefusal(text) {
    clearTimeout(refusal.timer);
    refusal = { text, timer: setTimeout(clearRefusal, REFUSAL_SHOWN_MS) };
  }

  async function undoLast() {
    // With nothing held here the service is asked anyway: it says why not ("hit 2 is already in
    // the analyzer's average"), or takes back a decision made from another page.
    if (!undo.supported || undo.busy || cap.state !== "running") return;
    undo.busy = true;
    renderUndo();
    try {
      const r = await api("POST", "/api/capture/undo", {});
      const index = r && Number.isInteger(r.index) ? r.index : r && Number.isInteger(r.number) ? r.number - 1 : undo.index;
      const h = cap.hits.get(index);
      if (h) {
        h.decided = false;
        h.held = false;
        delete h.heldAccepted;
        h.accepted = null;
        h.reason = "";
        upsertHitRow(h);
      }
      cap.pending = index;
      undo.index = null;
      undo.until = 0;
      sound.undo();
      renderPending();
      renderProgress();
    } catch (e) {
      if (e.status === 404 || e.status === 405) {
        undo.supported = false;
        DAQ.showError("this service cannot undo a decision (it has no /api/capture/undo)");
      }
      else if (e.status === 409) noteRefusal(e.message);
      undo.index = null;
      undo.until = 0;
    } finally {
      undo.busy = false;
      renderUndo();
    }
    rebuild(false);
  }

  function renderAverages(n) {
    $("n-averaged").textContent = fmt.plural(n || 0, "hit", "hits") + " averaged";
  }

  function renderLastRun() {
    const box = $("last-run");
    box.textContent = "";
    if (cap.last_run_id) {
      const id = cap.last_run_id;
      box.append(
        el("a", { href: DAQ.withToken("/api/runs/" + encodeURIComponent(id) + "/report"), target: "_blank", rel: "noopener" }, id)
      );
    } else {
      box.textContent = "none yet";
    }
    const out = $("run-outcome");
    const o = cap.last_outcome;
    out.textContent = o ? o + (cap.last_error ? ": " + cap.last_error : "") : "";
    out.className = "outcome" + (o ? " outcome-" + o : "");
    const note = $("outcome-note");
    if (note) {
      const ended = cap.ended_run_id;
      note.textContent =
        o && ended && ended !== cap.last_run_id ? "(capture " + ended + " was not stored)" : "";
    }
  }

  function renderResultsStatus() {
    const box = $("analysis-status");
    if (!results.runId) {
      box.textContent = "";
      return;
    }
    const a = results.analysisState || "none";
    const f = results.fitState || "none";
    let text = "Results of " + results.runId + ". Analysis: " + a;
    if (results.analysisError) text += " (" + results.analysisError + ")";
    text += " · fit: " + f;
    if (results.fitError) text += " (" + results.fitError + ")";
    box.textContent = text;
  }

  /* The band analysed and why, the synthesis error, and every caution of the analysis
   * as a visible "caution: ..." line: a result that may mislead is never silent. */
  function renderAnalysisNotes() {
    const a = results.analysis && typeof results.analysis === "object" ? results.analysis : null;
    $("analysis-band").textContent = a
      ? [DAQ.bandText(a.band), DAQ.synthesisText(a.synthesis_error)].filter(Boolean).join(" · ")
      : "";
    $("analysis-cautions").replaceChildren(...DAQ.cautionLines(DAQ.analysisCautions(a)));
  }

  function renderModes() {
    const body = $("modes-table").tBodies[0];
    const modes = (results.analysis && Array.isArray(results.analysis.modes) && results.analysis.modes) || [];
    body.replaceChildren(
      ...modes.map((m, i) =>
        el(
          "tr",
          null,
          el("td", { class: "num" }, String(i + 1)),
          el(
            "td",
            { class: "num frequency", title: m.uncertainty_from ? "± from " + m.uncertainty_from : null },
            DAQ.measured(m.frequency_hz, m.frequency_u_hz, fmt.fixed(m.frequency_hz, 4))
          ),
          el(
            "td",
            { class: "num damping", title: m.uncertainty_from ? "± from " + m.uncertainty_from : null },
            Number.isFinite(m.damping_ratio)
              ? DAQ.measured(m.damping_ratio * 100, Number.isFinite(m.damping_u) ? m.damping_u * 100 : null, fmt.sig(m.damping_ratio * 100, 3))
              : "n/a"
          )
        )
      )
    );
    const from = [...new Set(modes.map((m) => m.uncertainty_from).filter(Boolean))].sort();
    $("modes-note").textContent = modes.some((m) => typeof m.frequency_u_hz === "number" || typeof m.damping_u === "number")
      ? "± is the standard uncertainty of the value" + (from.length ? ", from " + from.join(", ") : "") + "."
      : "";
  }

  function renderTable2() {
    const body = $("table2").tBodies[0];
    const t2 = results.analysis && results.analysis.table2;
    const rows = (t2 && Array.isArray(t2.rows) && t2.rows) || [];
    const noBeam = t2 && !rows.length && t2.beam;
    $("table2-caption").textContent =
      t2 && !noBeam
        ? [t2.beam ? "beam: " + t2.beam : null, t2.n_functions ? "Ritz N = " + t2.n_functions : null]
            .filter(Boolean)
            .join(", ")
        : "";
    if (noBeam) {
      // e.g. "no beam model for this run: it records no test article"
      body.replaceChildren(el("tr", { class: "empty-row no-beam" }, el("td", { colspan: "6" }, String(t2.beam))));
      return;
    }
    body.replaceChildren(
      ...rows.map((r) =>
        el(
          "tr",
          null,
          el("td", { class: "num" }, r.mode === undefined || r.mode === null ? "–" : String(r.mode)),
          el("td", { class: "num" }, fmt.fixed(r.ritz_hz, 2)),
          el("td", { class: "num" }, fmt.fixed(r.exact_hz, 2)),
          el("td", { class: "num" }, fmt.fixed(r.identified_hz, 2)),
          el("td", { class: "num" }, fmt.fixed(r.difference_exact_pct, 2)),
          el("td", { class: "num" }, fmt.pct(r.damping_ratio, 3))
        )
      )
    );
  }

  /* "R12", "R1_2", "R(1,2)" -> [0, 1] (0-based); null when the name does not say.
   * Without a separator the digits split in two halves ("R1012" -> 10, 12); an odd
   * count ("R110") takes the split whose indices both lie in 1..n. */
  function termIndices(name, n) {
    const s = String(name).trim();
    let m = /^R_?\(?(\d+)\s*[,_ ]\s*(\d+)\)?$/.exec(s);
    let pairs;
    if (m) {
      pairs = [[Number(m[1]), Number(m[2])]];
    } else {
      m = /^R_?(\d+)$/.exec(s);
      if (!m || m[1].length < 2) return null;
      const d = m[1];
      const h = Math.floor(d.length / 2);
      pairs =
        d.length % 2 === 0
          ? [[Number(d.slice(0, h)), Number(d.slice(h))]]
          : [
              [Number(d.slice(0, h)), Number(d.slice(h))],
              [Number(d.slice(0, h + 1)), Number(d.slice(h + 1))],
            ];
    }
    const ok = pairs.find(([i, j]) => i >= 1 && j >= 1 && i <= n && j <= n);
    return ok ? [ok[0] - 1, ok[1] - 1] : null;
  }

  function chooseFit() {
    const fits = results.fits || {};
    const names = Object.keys(fits);
    if (!names.length) return null;
    const select = $("fit-select");
    const pref = results.preferredFit;
    let pick = null;
    if (pref) pick = names.find((n) => n === pref) || names.find((n) => fits[n] && fits[n].method === pref) || null;
    if (!pick && select.value && names.includes(select.value)) pick = select.value;
    return pick || names[0];
  }

  function renderFits() {
    const table = $("damping-matrix");
    const body = table.tBodies[0];
    const summary = $("fit-summary");
    const select = $("fit-select");
    const fits = results.fits || {};
    const names = Object.keys(fits);

    select.hidden = names.length < 2;
    select.replaceChildren(...names.map((n) => el("option", { value: n }, n)));
    const name = chooseFit();
    if (name) select.value = name;

    const fit = name ? fits[name] : null;
    $("fit-cautions").replaceChildren(...DAQ.cautionLines(fit && fit.cautions));
    if (table.tHead) table.tHead.remove();
    if (!fit || !Array.isArray(fit.damping_matrix)) {
      body.replaceChildren();
      summary.textContent =
        results.fitState === "failed" ? "The fit failed" + (results.fitError ? ": " + results.fitError : ".") : "No fit yet.";
      return;
    }
    const R = fit.damping_matrix;
    const n = R.length;
    const unc = fit.uncertainty || {};
    const terms = new Map(); // "i,j" -> {std, determined}
    (unc.names || []).forEach((nm, k) => {
      const ij = termIndices(nm, n);
      if (!ij) return;
      terms.set(ij[0] + "," + ij[1], {
        std: Array.isArray(unc.std) ? unc.std[k] : undefined,
        determined: Array.isArray(unc.determined) ? unc.determined[k] : undefined,
      });
    });
    const term = (i, j) => terms.get(i + "," + j) || terms.get(j + "," + i) || null;
    // What ± is, in `daq fit`'s words (daq/cli/commands/fit.py): the Fisher std, or the
    // larger of it and the per-hit refits' spread for the terms that had hits to refit.
    const sources = Array.isArray(unc.std_source) ? unc.std_source : [];
    const fromHits = (unc.names || []).filter((nm, k) => sources[k] === "hits");
    const label = fromHits.length
      ? "the larger of the Fisher std and the per-hit refits' spread / sqrt(n) (per-hit for " + fromHits.join(", ") + ")"
      : "the Fisher (Cramér-Rao) std";
    $("fit-std-note").textContent =
      "Each cell: R (N s/m) ± " + label + "; a trailing ? marks a term the data do not determine.";

    const head = table.createTHead();
    head.append(el("tr", null, el("th", null, ""), ...R.map((_, j) => el("th", { class: "num" }, String(j + 1)))));
    body.replaceChildren(
      ...R.map((row, i) =>
        el(
          "tr",
          null,
          el("th", { scope: "row" }, String(i + 1)),
          ...(row || []).map((v, j) => {
            const t = term(i, j);
            let text = fmt.sig(v, 4);
            if (t && t.std !== undefined && t.std !== null) text += " ± " + fmt.sig(t.std, 2);
            const undetermined = t && t.determined === false;
            if (undetermined) text += "?";
            return el(
              "td",
              { class: "num" + (undetermined ? " undetermined" : ""), title: undetermined ? "not determined by the data" : null },
              text
            );
          })
        )
      )
    );
    const parts = [];
    parts.push("method: " + (fit.method || name));
    // Psi in the unit of what was fitted, as the report says it: the response (time
    // records) or the accelerance (the FRF).
    const psiUnit = fit.domain === "frequency" ? " (m/s²)/N" : " m/s²";
    parts.push("Psi = " + fmt.sig(fit.psi, 4) + psiUnit);
    parts.push("noise floor = " + fmt.sig(fit.psi_noise_floor, 4) + psiUnit);
    if (Array.isArray(fit.modes) && fit.modes.length) {
      parts.push(
        "modes: " +
          fit.modes.map((m) => fmt.fixed(m.frequency_hz, 2) + " Hz (" + fmt.pct(m.damping_ratio, 3) + " %)").join(", ")
      );
    }
    summary.textContent = parts.join(" · ");
  }

  function renderResults() {
    renderResultsStatus();
    renderAnalysisNotes();
    renderModes();
    renderTable2();
    renderFits();
  }

  function renderAll() {
    renderState();
    renderSettings();
    renderSetupLine();
    renderHitsTable();
    renderPending();
    renderLastRun();
  }

  /* --------------------------------------------------------- traces, FRF */

  function peakAbs(y) {
    let m = 0;
    for (const v of y) if (Number.isFinite(v) && Math.abs(v) > m) m = Math.abs(v);
    return m;
  }

  /* A window (0..1 on the time axis) drawn to the trace's peak; none when the service does not send it. */
  function windowOver(win, trace) {
    if (!Array.isArray(win) || win.length !== trace.length) return [];
    const peak = peakAbs(trace) || 1;
    return win.map((w) => (Number.isFinite(w) ? w * peak : null));
  }

  /* The force pulse zoomed: from the peak, ± a few pulse widths, at least ± 12 ms so that a
   * second hit 10 ms later shows; the whole record if it is shorter. */
  function showPulse(t, force, fs) {
    const n = force.length;
    if (!n) {
      plots.pulse.clear();
      return;
    }
    let k = 0;
    for (let i = 1; i < n; i++) if (Math.abs(force[i]) > Math.abs(force[k])) k = i;
    const peak = Math.abs(force[k]);
    let lo = k;
    let hi = k;
    while (lo > 0 && Math.abs(force[lo - 1]) > 0.1 * peak) lo--;
    while (hi < n - 1 && Math.abs(force[hi + 1]) > 0.1 * peak) hi++;
    const widthS = (hi - lo + 1) / fs;
    const halfS = Math.max(0.012, 4 * widthS);
    const half = Math.max(8, Math.ceil(halfS * fs));
    const a = Math.max(0, k - Math.floor(half / 3));
    const b = Math.min(n, k + half + 1);
    plots.pulse.setData(t.slice(a, b), force.slice(a, b));
  }

  function showTraces(runId, h) {
    const fs = Number(h.sample_rate_hz);
    const start = Number(h.start_s) || 0;
    const force = Array.from(h.force_n || []);
    const resp = Array.from(h.response_m_s2 || []);
    const n = Math.max(force.length, resp.length);
    const t = new Array(n);
    for (let k = 0; k < n; k++) t[k] = (start + k / fs) * 1000;
    plots.force.setData(t, force, windowOver(h.force_window, force));
    plots.response.setData(t, resp, windowOver(h.response_window, resp));
    showPulse(t, force, fs);
    shownHitKey = runId + ":" + h.index;
    const label = "hit " + (Number.isInteger(h.number) ? h.number : numberOf(h.index));
    $("traces-hit").textContent = label;
    $("quality-hit").textContent = label;
    if ("force_spectrum" in h || "frf" in h) showQuality(h);
    markShownRow();
  }

  /* The same frequency axis, or nothing (a series must match the x axis). */
  function along(x, y) {
    return Array.isArray(y) && y.length === x.length ? y : [];
  }

  function showQuality(h) {
    const fsp = h.force_spectrum && typeof h.force_spectrum === "object" ? h.force_spectrum : null;
    const notes = [];
    if (fsp && Array.isArray(fsp.frequency_hz)) {
      const f = fsp.frequency_hz;
      let limit = [];
      if (Array.isArray(fsp.rolloff_limit_db)) limit = along(f, fsp.rolloff_limit_db);
      else if (Number.isFinite(fsp.rolloff_limit_db)) {
        const from = Number.isFinite(fsp.rolloff_hz) ? fsp.rolloff_hz : -Infinity;
        limit = f.map((v) => (v >= from ? fsp.rolloff_limit_db : null));
      }
      plots.spectrum.setData(f, along(f, fsp.level_db), limit);
      $("rolloff-note").textContent = Number.isFinite(fsp.rolloff_limit_db)
        ? "(limit " + fmt.sig(fsp.rolloff_limit_db, 3) + " dB" +
          (Number.isFinite(fsp.rolloff_hz) ? " from " + fmt.sig(fsp.rolloff_hz, 4) + " Hz" : "") + ")"
        : "";
    } else {
      plots.spectrum.clear();
      $("rolloff-note").textContent = "";
      notes.push("spectrum");
    }
    const frf = h.frf && typeof h.frf === "object" ? h.frf : null;
    const avg = h.average && typeof h.average === "object" ? h.average : null;
    if (frf && Array.isArray(frf.frequency_hz)) {
      const f = frf.frequency_hz;
      const same = avg && Array.isArray(avg.frequency_hz) && avg.frequency_hz.length === f.length;
      plots.hitFrf.setData(f, same ? along(f, avg.magnitude) : [], along(f, frf.magnitude));
      plots.hitPhase.setData(f, same ? along(f, avg.phase_deg) : [], along(f, frf.phase_deg));
      if (same) plots.hitCoherence.setData(f, along(f, avg.coherence));
      else plots.hitCoherence.clear();
    } else {
      plots.hitFrf.clear();
      plots.hitPhase.clear();
      plots.hitCoherence.clear();
      notes.push("FRF");
    }
    $("quality-note").textContent = notes.length === 2 ? "This service sends no per-hit quality data (spectrum, FRF) yet." : "";
  }

  function clearQuality() {
    plots.pulse.clear();
    plots.spectrum.clear();
    plots.hitFrf.clear();
    plots.hitPhase.clear();
    plots.hitCoherence.clear();
    $("quality-hit").textContent = "";
    $("rolloff-note").textContent = "";
    $("quality-note").textContent = "";
  }

  function clearTraces() {
    plots.force.clear();
    plots.response.clear();
    clearQuality();
    shownHitKey = null;
    $("traces-hit").textContent = "";
    markShownRow();
  }

  async function loadTraces(index) {
    const runId = cap.run_id;
    const my = ++tracesReq;
    let h;
    try {
      h = await api("GET", "/api/capture/hits/" + index, null, { quiet404: true });
    } catch (e) {
      return;
    }
    if (my !== tracesReq || runId !== cap.run_id) return; // a newer hit came meanwhile
    if (h) showTraces(runId, h);
  }

  function showFrf(runId, f) {
    plots.frf.setData(f.frequency_hz || [], f.frf_abs || []);
    plots.coherence.setData(f.frequency_hz || [], f.coherence || []);
    const n = f.n_averaged === undefined ? cap.accepted : f.n_averaged;
    renderAverages(n);
    shownFrfKey = runId + ":" + n;
  }

  function clearFrf() {
    plots.frf.clear();
    plots.coherence.clear();
    renderAverages(0);
    shownFrfKey = null;
  }

  async function loadFrf() {
    const runId = cap.run_id;
    const my = ++frfReq;
    let f;
    try {
      f = await api("GET", "/api/capture/frf", null, { quiet404: true });
    } catch (e) {
      return;
    }
    if (my !== frfReq || runId !== cap.run_id) return;
    if (f) showFrf(runId, f);
    else clearFrf();
  }

  async function loadInstrument() {
    const my = ++instrumentReq;
    try {
      const i = await api("GET", "/api/instrument");
      if (my === instrumentReq && i) {
        instrument = i;
        renderInstrument();
      }
    } catch (e) {
      /* shown in #error */
    }
  }

  /* ----------------------------------------------------------- results */

  function resetResults(runId) {
    Object.assign(results, {
      runId,
      analysis: null,
      fits: null,
      analysisState: null,
      analysisError: null,
      fitState: null,
      fitError: null,
    });
    resultsReq.states++;
    resultsReq.analysis++;
    resultsReq.fits++;
    renderResults();
  }

  /* The run's analysis and fit states; null when they could not be read. */
  async function loadStates(runId) {
    const my = ++resultsReq.states;
    let r;
    try {
      r = await api("GET", "/api/runs/" + encodeURIComponent(runId), null, { quiet404: true });
    } catch (e) {
      return null;
    }
    if (!r) return null;
    if (my === resultsReq.states && runId === results.runId) {
      results.analysisState = r.analysis_state || results.analysisState;
      results.fitState = r.fit_state || results.fitState;
      renderResultsStatus();
    }
    return r;
  }

  async function loadAnalysis(runId) {
    const my = ++resultsReq.analysis;
    let a;
    try {
      a = await api("GET", "/api/runs/" + encodeURIComponent(runId) + "/analysis", null, { quiet404: true });
    } catch (e) {
      return;
    }
    if (my !== resultsReq.analysis || runId !== results.runId) return;
    results.analysis = a;
    renderAnalysisNotes();
    renderModes();
    renderTable2();
  }

  async function loadFits(runId) {
    const my = ++resultsReq.fits;
    let f;
    try {
      f = await api("GET", "/api/runs/" + encodeURIComponent(runId) + "/fits", null, { quiet404: true });
    } catch (e) {
      return;
    }
    if (my !== resultsReq.fits || runId !== results.runId) return;
    results.fits = f && typeof f === "object" ? f : null;
    renderFits();
  }

  /* Everything about a run's results. Asks for the analysis and the fits only
   * when the run says they exist (no 404s to clutter the console), or when its
   * states could not be read. */
  async function loadResults(runId) {
    if (!runId) {
      resetResults(null);
      return;
    }
    if (results.runId !== runId) resetResults(runId);
    const r = await loadStates(runId);
    if (runId !== results.runId) return;
    const tasks = [];
    const hasAnalysis = !r || r.analysis_state === "done" || (r.analysis && typeof r.analysis === "object");
    const hasFits = !r || r.fit_state === "done" || (r.fits && Object.keys(r.fits).length > 0);
    if (hasAnalysis) tasks.push(loadAnalysis(runId));
    if (hasFits) tasks.push(loadFits(runId));
    await Promise.allSettled(tasks);
  }

  /* ----------------------------------------------------- snapshot, rebuild */

  let holding = false; // a snapshot is on its way: hold events back
  let held = [];

  function applySnapshot(s) {
    const newRun = s.run_id !== cap.run_id;
    cap.state = s.state || null;
    cap.run_id = s.run_id || null;
    cap.hits_wanted = s.hits_wanted || 0;
    cap.accepted = s.accepted || 0;
    cap.auto = Boolean(s.auto);
    cap.pending = s.pending === undefined ? null : s.pending;
    const before = newRun ? new Map() : cap.hits;
    cap.hits = new Map(
      (s.hits || []).map((h) => {
        const old = before.get(h.index);
        if (h.held && !h.decided && typeof h.held_accepted === "boolean") {
          // the service says which verdict it holds (a page opened during the hold)
          h.heldAccepted = h.held_accepted;
          if (!h.reason) h.reason = h.held_reason || "";
        } else if (h.held && !h.decided && old && typeof old.heldAccepted === "boolean") {
          h.heldAccepted = old.heldAccepted;
          if (!h.reason) h.reason = old.reason || "";
        }
        return [h.index, h];
      })
    );
    cap.settings = s.settings || null;
    cap.last_run_id = s.last_run_id || null;
    cap.last_outcome = s.last_outcome || null;
    cap.last_error = s.last_message || s.last_error || null; // the capture_ended message
    cap.ended_run_id = cap.state === "idle" && cap.last_outcome ? cap.run_id : null;
    cap.undo_window_s = typeof s.undo_window_s === "number" ? s.undo_window_s : cap.undo_window_s;
    cap.setup = s.setup && typeof s.setup === "object" ? s.setup : null;
    // the setup a capture that names none uses (a service that does not say: undefined)
    if ("next_setup" in s) cap.next_setup = s.next_setup && typeof s.next_setup === "object" ? s.next_setup : null;
    cap.transducers = s.transducers && typeof s.transducers === "object" ? s.transducers : null;
    cap.cautions = Array.isArray(s.cautions) ? s.cautions : [];
    snapshotUndo(s);
    if (newRun) {
      // another capture than the one on the plots: clear them until its data come
      tracesReq++;
      frfReq++;
      clearTraces();
      clearFrf();
    }
    renderAll();
  }

  /* A decision the service holds (undo_until_s seconds left): offer its undo. */
  function snapshotUndo(s) {
    let left = typeof s.undo_until_s === "number" ? s.undo_until_s : null;
    let index = null;
    for (const h of s.hits || []) {
      if (h.held || (typeof h.undo_until_s === "number" && h.undo_until_s > 0)) {
        if (typeof h.undo_until_s === "number") left = h.undo_until_s;
        index = h.index;
      }
    }
    if (left === null || left <= 0) {
      if (cap.state !== "running") undo.index = null;
      return;
    }
    if (index === null) {
      const decided = (s.hits || []).filter((h) => h.decided);
      if (!decided.length) return;
      index = decided[decided.length - 1].index;
    }
    const h = cap.hits.get(index);
    noteDecision(index, h && typeof h.heldAccepted === "boolean" ? h.heldAccepted : h && h.decided ? h.accepted : null, left);
  }

  let rebuildRunning = false;
  let rebuildAgain = false;
  let rebuildFull = false;

  /* Fetch the capture snapshot and whatever the page shows that is not current.
   * full: fetch everything again (after a (re)connection of the event stream). */
  async function rebuild(full) {
    rebuildFull = rebuildFull || Boolean(full);
    if (rebuildRunning) {
      rebuildAgain = true;
      return;
    }
    rebuildRunning = true;
    try {
      do {
        rebuildAgain = false;
        const f = rebuildFull;
        rebuildFull = false;
        await rebuildOnce(f);
      } while (rebuildAgain);
    } finally {
      rebuildRunning = false;
    }
  }

  async function rebuildOnce(full) {
    holding = true;
    let snap = null;
    try {
      snap = await api("GET", "/api/capture");
      if (snap) applySnapshot(snap);
    } catch (e) {
      snap = null;
    } finally {
      holding = false;
      const queue = held;
      held = [];
      for (const [fn, data] of queue) {
        try {
          fn(data);
        } catch (e) {
          console.error(e);
        }
      }
    }
    const tasks = [];
    if (full || !instrument.resource) tasks.push(loadInstrument());
    if (!snap) return Promise.allSettled(tasks);

    const latest = latestIndex();
    if (latest === null) {
      if (shownHitKey !== null) clearTraces();
    } else {
      const shownIndex = shownHitKey && shownHitKey.startsWith(cap.run_id + ":") ? Number(shownHitKey.split(":").pop()) : null;
      const stillThere = shownIndex !== null && cap.hits.has(shownIndex);
      if (full || !stillThere) tasks.push(loadTraces(latest));
    }

    if (cap.accepted > 0) {
      if (full || shownFrfKey !== cap.run_id + ":" + cap.accepted) tasks.push(loadFrf());
    } else if (shownFrfKey !== null || full) {
      clearFrf();
    }

    if (cap.last_run_id) {
      if (full || results.runId !== cap.last_run_id) tasks.push(loadResults(cap.last_run_id));
    } else if (results.runId !== null || full) {
      resetResults(null);
    }
    return Promise.allSettled(tasks);
  }

  /* ---------------------------------------------------------------- events */

  function on(type, fn) {
    events.on(type, (data) => {
      if (holding) held.push([fn, data]);
      else fn(data);
    });
  }

  const isCurrent = (ev) => ev && ev.run_id && ev.run_id === cap.run_id;
  const isLastRun = (ev) => ev && ev.run_id && ev.run_id === cap.last_run_id;

  on("capture_started", (ev) => {
    undo.index = null;
    undo.until = 0;
    soundedDecision.clear();
    cap.state = "running";
    cap.run_id = ev.run_id;
    cap.hits_wanted = ev.hits_wanted || 0;
    cap.auto = Boolean(ev.auto);
    cap.accepted = 0;
    cap.pending = null;
    cap.hits = new Map();
    cap.settings = null;
    cap.ended_run_id = null;
    // the last capture's setup is not this one's (the snapshot says this one's)
    cap.setup = ev.setup && typeof ev.setup === "object" ? ev.setup : null;
    cap.transducers = ev.transducers && typeof ev.transducers === "object" ? ev.transducers : null;
    tracesReq++;
    frfReq++;
    clearTraces();
    clearFrf();
    renderAll();
  });

  on("configured", (ev) => {
    if (!isCurrent(ev)) return;
    cap.settings = ev.settings || null;
    renderSettings();
    if (!cap.setup && !cap.transducers) rebuild(false); // a capture started elsewhere: its setup
    if (ev.identification) {
      instrument = Object.assign({}, instrument, { identification: ev.identification, connected: true });
      instrumentReq++;
      renderInstrument();
    }
  });

  on("hit", (ev) => {
    if (!isCurrent(ev)) return;
    const h = summaryFromEvent(ev);
    cap.hits.set(h.index, h);
    if (typeof ev.accepted_so_far === "number") cap.accepted = ev.accepted_so_far;
    if (!cap.auto) cap.pending = h.index;
    clearRefusal();
    upsertHitRow(h);
    tracesReq++; // a fetch of older traces must not overwrite these
    if (Array.isArray(ev.force_n)) showTraces(cap.run_id, ev);
    loadTraces(h.index); // with its quality: windows, spectrum, FRF
    sound.hit();
    renderPending();
    renderProgress();
  });

  on("hit_decided", (ev) => {
    if (!isCurrent(ev)) return;
    const h = cap.hits.get(ev.index) || { index: ev.index, checks: [], passed: true };
    h.decided = true;
    h.accepted = Boolean(ev.accepted);
    h.reason = ev.reason || "";
    cap.hits.set(ev.index, h);
    if (typeof ev.accepted_so_far === "number") cap.accepted = ev.accepted_so_far;
    if (typeof ev.accepted_against_checks === "boolean") h.accepted_against_checks = ev.accepted_against_checks;
    h.held = false;
    delete h.heldAccepted;
    if (undo.index === ev.index) {
      undo.index = null; // it is in the analyzer now
      undo.until = 0;
    }
    if (Number.isInteger(ev.number)) h.number = ev.number;
    if (cap.pending === ev.index) cap.pending = null;
    if (!soundedDecision.has(cap.run_id + ":" + ev.index + ":" + h.accepted)) {
      soundedDecision.add(cap.run_id + ":" + ev.index + ":" + h.accepted);
      if (h.accepted) sound.accept();
      else sound.reject();
    }
    if (typeof ev.undo_until_s === "number" && ev.undo_until_s > 0) noteDecision(ev.index, h.accepted, ev.undo_until_s);
    upsertHitRow(h);
    renderPending();
    renderProgress();
  });

  on("decision_held", (ev) => {
    if (!isCurrent(ev)) return;
    const h = cap.hits.get(ev.index);
    if (!h) return;
    h.held = true;
    h.decided = false;
    h.heldAccepted = Boolean(ev.accepted);
    h.reason = ev.reason || "";
    if (cap.pending === ev.index) cap.pending = null;
    noteDecision(ev.index, h.heldAccepted, ev.undo_until_s);
    const key = cap.run_id + ":" + ev.index + ":" + h.heldAccepted;
    if (!soundedDecision.has(key)) {
      soundedDecision.add(key);
      if (h.heldAccepted) sound.accept();
      else sound.reject();
    }
    upsertHitRow(h);
    renderPending();
  });

  on("decision_undone", (ev) => {
    if (!isCurrent(ev)) return;
    const h = cap.hits.get(ev.index);
    if (h) {
      h.held = false;
      h.decided = false;
      delete h.heldAccepted;
      h.reason = "";
      upsertHitRow(h);
    }
    cap.pending = ev.index;
    if (undo.index === ev.index) {
      undo.index = null;
      undo.until = 0;
    }
    soundedDecision.clear();
    renderPending();
  });

  on("frf", (ev) => {
    if (!isCurrent(ev)) return;
    frfReq++;
    showFrf(cap.run_id, ev);
    // the hit on the plots is drawn over the average: draw it over the new one
    if (shownHitKey && shownHitKey.startsWith(cap.run_id + ":")) loadTraces(Number(shownHitKey.split(":").pop()));
  });

  on("run_sealed", (ev) => {
    if (!isCurrent(ev)) return;
    cap.last_run_id = ev.run_id;
    renderLastRun();
    loadResults(ev.run_id);
  });

  on("capture_ended", (ev) => {
    if (!isCurrent(ev)) return;
    cap.state = "idle";
    cap.pending = null;
    cap.last_outcome = ev.outcome || null;
    cap.last_error = ev.message || null;
    cap.ended_run_id = ev.run_id;
    renderState();
    renderPending();
    renderLastRun();
    renderSetupLine(); // "This capture" becomes "Last capture", and the next one's is said
  });

  function resultsEvent(fn) {
    return (ev) => {
      if (!isLastRun(ev)) return;
      if (results.runId !== ev.run_id) resetResults(ev.run_id);
      fn(ev);
      renderResultsStatus();
    };
  }

  on(
    "analysis_started",
    resultsEvent(() => {
      resultsReq.states++;
      results.analysisState = "running";
      results.analysisError = null;
    })
  );
  on(
    "analysis_done",
    resultsEvent((ev) => {
      resultsReq.states++;
      results.analysisState = "done";
      results.analysisError = null;
      loadAnalysis(ev.run_id);
    })
  );
  on(
    "analysis_failed",
    resultsEvent((ev) => {
      resultsReq.states++;
      results.analysisState = "failed";
      results.analysisError = ev.error || null;
    })
  );
  on(
    "fit_done",
    resultsEvent((ev) => {
      resultsReq.states++;
      results.fitState = "done";
      results.fitError = null;
      if (ev.method) results.preferredFit = ev.method;
      loadFits(ev.run_id);
    })
  );
  on(
    "fit_failed",
    resultsEvent((ev) => {
      resultsReq.states++;
      results.fitState = "failed";
      results.fitError = (ev.method ? ev.method + ": " : "") + (ev.error || "failed");
      renderFits();
    })
  );

  on("instrument", (ev) => {
    instrumentReq++;
    instrument = Object.assign({}, instrument, ev);
    renderInstrument();
  });

  /* --------------------------------------------------------------- actions */

  $("capture-form").addEventListener("submit", async (e) => {
    e.preventDefault();
    const hitsInput = $("hits-wanted");
    const hits = Number(hitsInput.value);
    if (!Number.isInteger(hits) || hits < 1 || hits > 999) {
      DAQ.showError("Hits wanted: a whole number from 1 to 999.");
      hitsInput.focus();
      return;
    }
    const body = {
      hits,
      operator: $("operator").value.trim(),
      note: $("note").value.trim(),
      auto: $("auto").checked,
    };
    // the setup, test and point chosen (station.js); nothing when left at the service's own
    if (DAQ.station && typeof DAQ.station.captureFields === "function") Object.assign(body, DAQ.station.captureFields());
    starting = true;
    renderState();
    try {
      await api("POST", "/api/capture", body);
      try {
        localStorage.setItem("daq-operator", body.operator);
      } catch (err) {
        /* not kept */
      }
    } catch (err) {
      /* #error says why */
    } finally {
      starting = false;
      renderState();
    }
    rebuild(false);
  });

  $("stop").addEventListener("click", async () => {
    try {
      await api("POST", "/api/capture/stop");
    } catch (e) {
      /* #error says why */
    }
    rebuild(false);
  });

  $("abort").addEventListener("click", async () => {
    const n = cap.hits.size;
    const ok = window.confirm(
      "Abort the capture? Its " + fmt.plural(n, "hit", "hits") + " will be discarded and nothing is stored."
    );
    if (!ok) return;
    try {
      await api("POST", "/api/capture/abort");
    } catch (e) {
      /* #error says why */
    }
    rebuild(false);
  });

  async function decide(accept) {
    const index = cap.pending;
    if (index === null || index === undefined || deciding) return;
    const h = cap.hits.get(index);
    const body = { index, accept };
    if (!accept) {
      const typed = $("reject-reason").value.trim();
      const reason = typed || (h && !h.passed ? h.suggested_reason : "");
      if (reason) body.reason = reason;
    }
    deciding = true;
    renderPending();
    try {
      const r = await api("POST", "/api/capture/decision", body);
      // The hit_decided event confirms; show the decision now so a second tap cannot repeat it.
      const hit = cap.hits.get(index);
      if (hit && !hit.decided) {
        if (cap.undo_window_s) {
          hit.held = true; // until the analyzer gets it (hit_decided)
          hit.heldAccepted = accept;
        } else {
          hit.decided = true;
          hit.accepted = r && typeof r.accepted === "boolean" ? r.accepted : accept;
        }
        hit.reason = accept ? "" : body.reason || "";
        upsertHitRow(hit);
      }
      if (cap.pending === index) cap.pending = null;
      noteDecision(index, accept, r && typeof r.undo_until_s === "number" ? r.undo_until_s : undefined);
      const key = cap.run_id + ":" + index + ":" + accept;
      if (!soundedDecision.has(key)) {
        soundedDecision.add(key);
        if (accept) sound.accept();
        else sound.reject();
      }
    } catch (e) {
      if (e.status === 409) rebuild(false);
    } finally {
      deciding = false;
      renderPending();
    }
  }

  $("accept").addEventListener("click", () => decide(true));
  $("reject").addEventListener("click", () => decide(false));
  $("undo").addEventListener("click", () => undoLast());
  $("reject-reason").addEventListener("keydown", (e) => {
    if (e.key === "Enter") {
      e.preventDefault();
      decide(false);
    }
  });

  $("hits-table").tBodies[0].addEventListener("click", (e) => {
    const row = e.target.closest("tr[data-index]");
    if (!row) return;
    loadTraces(Number(row.dataset.index));
  });

  $("fit-select").addEventListener("change", () => {
    results.preferredFit = $("fit-select").value;
    renderFits();
  });

  DAQ.onToken(() => renderLastRun());

  /* ------------------------------------------------------ keys, large display */

  function typing(target) {
    if (!target || !(target instanceof Element)) return false;
    if (target.isContentEditable) return true;
    const tag = target.tagName;
    if (tag === "TEXTAREA" || tag === "SELECT") return true;
    if (tag !== "INPUT") return false;
    const type = (target.getAttribute("type") || "text").toLowerCase();
    return !["checkbox", "radio", "button", "submit", "reset"].includes(type);
  }

  function setLarge(large) {
    document.body.classList.toggle("large", large);
    const b = $("large-toggle");
    b.setAttribute("aria-pressed", large ? "true" : "false");
    b.replaceChildren(large ? "Normal " : "Large ", el("kbd", null, "L"));
    const url = new URL(window.location.href);
    if (large) url.searchParams.set("display", "large");
    else url.searchParams.delete("display");
    window.history.replaceState(null, "", url.pathname + url.search + url.hash);
  }

  /* a: accept, r: reject, u: undo, s: start, x or Escape: stop, l: large display;
   * not while typing in a field, nor with Ctrl, Alt or Meta (the browser's own keys). */
  document.addEventListener("keydown", (e) => {
    if (e.defaultPrevented || e.ctrlKey || e.altKey || e.metaKey || e.isComposing) return;
    if (typing(e.target)) {
      // Escape leaves the field, so that the keys work again without reaching for the mouse
      if (e.key === "Escape") e.target.blur();
      return;
    }
    sound.wake();
    const key = e.key.length === 1 ? e.key.toLowerCase() : e.key;
    let done = true;
    if (key === "a") {
      if (!$("accept").disabled) decide(true);
    } else if (key === "r") {
      if (!$("reject").disabled) decide(false);
    } else if (key === "u") {
      undoLast();
    } else if (key === "s") {
      if (!$("start").disabled) $("capture-form").requestSubmit();
    } else if (key === "x" || key === "Escape") {
      if (!$("stop").disabled) $("stop").click();
      else done = key !== "Escape" ? true : false;
    } else if (key === "l") {
      setLarge(!document.body.classList.contains("large"));
    } else {
      done = false;
    }
    if (done) e.preventDefault();
  });

  $("large-toggle").addEventListener("click", () => setLarge(!document.body.classList.contains("large")));
  $("sound-toggle").addEventListener("click", () => sound.toggle());
  sound.render();
  if (new URLSearchParams(window.location.search).get("display") === "large") setLarge(true);

  /* ------------------------------------------------------------------ start */

  try {
    const op = localStorage.getItem("daq-operator");
    if (op && !$("operator").value) $("operator").value = op;
  } catch (e) {
    /* nothing kept */
  }

  renderAll();
  renderAverages(0);
  renderResults();

  let helloSeen = false;
  events.onHello(() => {
    helloSeen = true;
    rebuild(true);
  });
  events.start();
  // If the event stream does not come up quickly (e.g. it needs a token), show what the API says anyway.
  setTimeout(() => {
    if (!helloSeen) rebuild(true);
  }, 1500);
})();
