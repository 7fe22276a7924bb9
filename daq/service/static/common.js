/* Shared by the live capture page and the runs page of `daq serve`.
 *
 * window.DAQ gives:
 *   token handling   DAQ.getToken(), DAQ.setToken(t), DAQ.withToken(url), DAQ.onToken(fn)
 *   requests         DAQ.api(method, path, body, {quiet404}) -> parsed JSON (or text), null on a quiet 404
 *   errors           DAQ.showError(text), DAQ.clearError()
 *   live events      DAQ.events.on(type, fn), DAQ.events.onHello(fn), DAQ.events.start()
 *   formatting       DAQ.fmt.fixed / pct / sig / time, DAQ.el(tag, attrs, ...children)
 *   plots            DAQ.plot(container, options) on top of uPlot
 *
 * Plain ES2020, no build step, nothing fetched from outside the page's own server.
 */
(function () {
  "use strict";

  const TOKEN_KEY = "daq-token";

  /* ---------------------------------------------------------------- token */

  let token = null;
  const tokenListeners = [];

  function readStoredToken() {
    try {
      return localStorage.getItem(TOKEN_KEY);
    } catch (e) {
      return null; // storage disabled: keep the token in memory only
    }
  }

  function setToken(value) {
    token = value ? String(value).trim() : null;
    try {
      if (token) localStorage.setItem(TOKEN_KEY, token);
      else localStorage.removeItem(TOKEN_KEY);
    } catch (e) {
      /* in memory only */
    }
    for (const fn of tokenListeners) fn(token);
  }

  function getToken() {
    return token;
  }

  /* `daq serve` prints http://host:port/#token=<hex>: take it from the fragment,
   * keep it, and take it out of the address bar. */
  function takeTokenFromFragment() {
    const hash = window.location.hash.replace(/^#/, "");
    if (!hash) return;
    const params = new URLSearchParams(hash);
    const t = params.get("token");
    if (!t) return;
    params.delete("token");
    const rest = params.toString();
    const url = window.location.pathname + window.location.search + (rest ? "#" + rest : "");
    window.history.replaceState(null, "", url);
    token = t.trim();
    try {
      localStorage.setItem(TOKEN_KEY, token);
    } catch (e) {
      /* in memory only */
    }
  }

  token = readStoredToken();
  takeTokenFromFragment();

  /* The URL with ?token=<token> (or &token=) when a token is known: for links
   * (downloads, report) and the event stream, which cannot send headers. */
  function readsNeedToken() {
    /* The service says so in the page (a <meta> it fills in); on loopback it is false,
     * and a link that carried the token would put it in history and in copied links. */
    const meta = document.querySelector('meta[name="daq-reads-need-token"]');
    return !meta || meta.content !== "false";
  }

  function withToken(url) {
    if (!token || !readsNeedToken()) return url;
    const sep = url.includes("?") ? "&" : "?";
    return url + sep + "token=" + encodeURIComponent(token);
  }

  /* -------------------------------------------------------- small DOM kit */

  function $(id) {
    return document.getElementById(id);
  }

  /* el("td", {class: "x", title: "y"}, "text", otherNode) */
  function el(tag, attrs, ...children) {
    const node = document.createElement(tag);
    if (attrs) {
      for (const [k, v] of Object.entries(attrs)) {
        if (v === null || v === undefined || v === false) continue;
        if (k === "class") node.className = v;
        else if (k === "text") node.textContent = v;
        else if (k === "dataset") Object.assign(node.dataset, v);
        else node.setAttribute(k, v === true ? "" : String(v));
      }
    }
    for (const c of children) {
      if (c === null || c === undefined || c === false) continue;
      node.append(c instanceof Node ? c : String(c));
    }
    return node;
  }

  /* ---------------------------------------------------------- error line */

  let errorFrom = null; // "read" or "write": which kind of request set #error

  function showError(text, from) {
    const box = $("error");
    if (box) box.textContent = text;
    errorFrom = from || "write";
  }

  function clearError() {
    const box = $("error");
    if (box) box.textContent = "";
    errorFrom = null;
  }

  /* FastAPI answers {"detail": "text"} or, for a bad body, {"detail": [{loc, msg}, ...]}. */
  function detailText(body, response) {
    const d = body && typeof body === "object" ? body.detail : null;
    if (typeof d === "string" && d) return d;
    if (Array.isArray(d) && d.length) {
      return d
        .map((item) => {
          if (!item || typeof item !== "object") return String(item);
          const loc = Array.isArray(item.loc) ? item.loc.filter((p) => p !== "body").join(".") : "";
          return (loc ? loc + ": " : "") + (item.msg || JSON.stringify(item));
        })
        .join("; ");
    }
    if (typeof body === "string" && body.trim()) return body.trim().slice(0, 300);
    return response.status + " " + (response.statusText || "error");
  }

  /* ------------------------------------------------------------ token panel */

  function showTokenPanel(message) {
    const panel = $("token-panel");
    if (!panel) return;
    const msg = $("token-message");
    if (msg && message) msg.textContent = message;
    panel.hidden = false;
    const input = $("token-input");
    if (input && document.activeElement !== input) input.focus();
  }

  function hideTokenPanel() {
    const panel = $("token-panel");
    if (panel) panel.hidden = true;
  }

  function wireTokenPanel() {
    const save = $("token-save");
    const input = $("token-input");
    if (!save || !input) return;
    const submit = (ev) => {
      if (ev) ev.preventDefault();
      const v = input.value.trim();
      if (!v) return;
      input.value = "";
      hideTokenPanel();
      clearError();
      setToken(v);
    };
    save.addEventListener("click", submit);
    input.addEventListener("keydown", (ev) => {
      if (ev.key === "Enter") submit(ev);
    });
  }

  /* --------------------------------------------------------------- api() */

  class ApiError extends Error {
    constructor(message, status, body) {
      super(message);
      this.status = status;
      this.body = body;
    }
  }

  /* api("POST", "/api/capture", {hits: 5}) -> the parsed answer.
   * Adds the bearer token; a 401 opens the token panel; any other failure puts
   * the answer's detail in #error and throws an ApiError. A success clears an
   * error left by the same kind of request (a read clears a read's error, an
   * action clears any error). opts.quiet404: a 404 returns null silently. */
  async function api(method, path, body, opts) {
    opts = opts || {};
    const kind = method.toUpperCase() === "GET" ? "read" : "write";
    const headers = { Accept: "application/json" };
    if (token) headers.Authorization = "Bearer " + token;
    const init = { method: method.toUpperCase(), headers, cache: "no-store" };
    if (body !== undefined && body !== null) {
      headers["Content-Type"] = "application/json";
      init.body = JSON.stringify(body);
    }
    let response;
    try {
      response = await fetch(path, init);
    } catch (e) {
      const text = "cannot reach the service (" + (e && e.message ? e.message : e) + ")";
      if (!opts.silent) showError(text, kind);
      throw new ApiError(text, 0, null);
    }
    const type = response.headers.get("Content-Type") || "";
    let data = null;
    if (response.status !== 204) {
      try {
        data = type.includes("json") ? await response.json() : await response.text();
      } catch (e) {
        data = null;
      }
    }
    if (response.ok) {
      if (kind === "write" || errorFrom === "read") clearError();
      return data;
    }
    if (response.status === 404 && opts.quiet404) return null;
    const text = detailText(data, response);
    if (response.status === 401) {
      showTokenPanel("The service needs its token (" + text + "): paste the token `daq serve --show-token` prints.");
    } else if (!opts.silent) {
      showError(text, kind);
    }
    throw new ApiError(text, response.status, data);
  }

  /* ------------------------------------------------------------ live events */

  /* One EventSource on /api/events (with ?token= when known). On a dropped
   * connection the browser reconnects by itself and sends Last-Event-ID; if it
   * gives up (e.g. a 401), we open a new one after a pause. Each connection
   * starts with a `hello` event: the pages rebuild their state from the API then,
   * so nothing missed between connections matters. If hello's last_id is below
   * the last id we saw, the service restarted and numbers its events afresh: our
   * Last-Event-ID would hide its new events, so we open a fresh stream. */
  const events = (function () {
    const handlers = new Map(); // type -> [fn]
    const helloHandlers = [];
    let source = null;
    let lastId = null;
    let retryTimer = null;
    let retryDelay = 1000;
    let started = false;

    function setStatus(state, text) {
      const box = $("conn-status");
      if (!box) return;
      box.textContent = text;
      box.className = "conn conn-" + state;
    }

    function dispatch(type, ev) {
      if (ev.lastEventId) lastId = ev.lastEventId;
      let data = null;
      try {
        data = ev.data ? JSON.parse(ev.data) : {};
      } catch (e) {
        console.warn("event", type, "with data that is not JSON:", ev.data);
        return;
      }
      for (const fn of handlers.get(type) || []) {
        try {
          fn(data, ev);
        } catch (e) {
          console.error("handler of event", type, e);
        }
      }
    }

    function listen(es, type) {
      es.addEventListener(type, (ev) => dispatch(type, ev));
    }

    function url() {
      return withToken("/api/events");
    }

    function open() {
      clearTimeout(retryTimer);
      retryTimer = null;
      if (source) source.close();
      setStatus("connecting", "connecting…");
      const es = new EventSource(url());
      source = es;
      es.addEventListener("hello", (ev) => {
        let data = {};
        try {
          data = JSON.parse(ev.data || "{}");
        } catch (e) {
          /* keep {} */
        }
        const serverLast = Number(data.last_id);
        if (lastId !== null && Number.isFinite(serverLast) && Number(lastId) > serverLast) {
          lastId = null; // a restarted service: start afresh, without Last-Event-ID
          open();
          return;
        }
        retryDelay = 1000;
        setStatus("live", "live");
        for (const fn of helloHandlers) {
          try {
            fn(data);
          } catch (e) {
            console.error("hello handler", e);
          }
        }
      });
      for (const type of handlers.keys()) listen(es, type);
      es.onerror = () => {
        if (source !== es) return;
        if (es.readyState === EventSource.CLOSED) {
          // The browser gave up: find out why (a 401 opens the token panel) and retry.
          setStatus("down", "no live updates, retrying…");
          api("GET", "/api/health", null, { silent: true }).catch(() => {});
          retryTimer = setTimeout(open, retryDelay);
          retryDelay = Math.min(retryDelay * 2, 30000);
        } else {
          setStatus("connecting", "reconnecting…");
        }
      };
    }

    return {
      on(type, fn) {
        if (!handlers.has(type)) {
          handlers.set(type, []);
          if (source) listen(source, type);
        }
        handlers.get(type).push(fn);
      },
      onHello(fn) {
        helloHandlers.push(fn);
      },
      start() {
        started = true;
        open();
      },
      restart() {
        if (started) open();
      },
    };
  })();

  /* A new token: reconnect the event stream with it. */
  tokenListeners.push(() => events.restart());

  /* ------------------------------------------------------------- formatting */

  const DASH = "–";

  function isNum(x) {
    return typeof x === "number" && Number.isFinite(x);
  }

  /* "-0.00" -> "0.00" */
  function noNegativeZero(text) {
    return /^-0(\.0*)?$/.test(text) ? text.slice(1) : text;
  }

  const fmt = {
    /* fixed(12.3456, 2) -> "12.35"; null, NaN -> "–" */
    fixed(x, digits) {
      return isNum(x) ? noNegativeZero(x.toFixed(digits)) : DASH;
    },
    /* a ratio as percent: pct(0.0123, 2) -> "1.23" */
    pct(ratio, digits) {
      return isNum(ratio) ? noNegativeZero((ratio * 100).toFixed(digits)) : DASH;
    },
    /* n significant digits, exponent only for very small or large values */
    sig(x, n) {
      if (!isNum(x)) return x === Infinity || x === -Infinity ? (x > 0 ? "∞" : "-∞") : DASH;
      n = n || 4;
      if (x === 0) return "0";
      const a = Math.abs(x);
      if (a >= 1e-3 && a < 1e6) return String(Number(x.toPrecision(n)));
      return x.toExponential(n - 1).replace("e+", "e");
    },
    /* an ISO time as local "2024-05-01 14:03:22" */
    time(iso) {
      if (!iso) return DASH;
      const d = new Date(iso);
      if (Number.isNaN(d.getTime())) return String(iso);
      const p = (v) => String(v).padStart(2, "0");
      return (
        d.getFullYear() + "-" + p(d.getMonth() + 1) + "-" + p(d.getDate()) + " " +
        p(d.getHours()) + ":" + p(d.getMinutes()) + ":" + p(d.getSeconds())
      );
    },
    plural(n, one, many) {
      return n + " " + (n === 1 ? one : many);
    },
  };

  /* --------------------------------------------------------------- cautions */

  /* Stored texts (a list of sentences) as strings; anything else: none. */
  function texts(list) {
    return Array.isArray(list) ? list.filter((t) => t !== null && t !== undefined).map(String) : [];
  }

  /* An analysis summary's cautions as `daq analyze` prints them: the windows' when the
   * source does not say which it applied, then the summary's own `cautions`. */
  function analysisCautions(summary) {
    if (!summary || typeof summary !== "object") return [];
    const out = texts(summary.cautions);
    const from = summary.windows && typeof summary.windows === "object" ? summary.windows.from : null;
    // An analysis stored before it was one of the summary's cautions.
    if (typeof from === "string" && from.startsWith("unknown") && !out.includes("windows " + from)) {
      out.unshift("windows " + from);
    }
    return out;
  }

  /* One visible "caution: ..." line per text, each an element `tag` (li, p, div).
   * Text only (textContent): the sentences may come from a foreign run. */
  function cautionLines(list, tag) {
    return texts(list).map((t) => el(tag || "li", { class: "caution" }, "caution: " + t));
  }

  /* "band 1.088–399.4 Hz: <reason>" of an analysis summary (edges to four significant
   * digits, as `daq analyze` writes them); "" when it has none. */
  function bandText(band) {
    if (!band || typeof band !== "object") return "";
    let text = "band " + fmt.sig(band.low_hz, 4) + "–" + fmt.sig(band.high_hz, 4) + " Hz";
    if (band.reason) text += ": " + String(band.reason);
    return text;
  }

  /* "synthesis error 38 %" (a fraction stored); "" when unknown. */
  function synthesisText(error) {
    return isNum(error) ? "synthesis error " + fmt.sig(error * 100, 3) + " %" : "";
  }

  /* "3896 ± 12", "0.0347 ± 0.0040": a value and its standard uncertainty as `daq analyze`
   * and the report write them (analysis/measurement_text.py): u to two significant digits,
   * the value to the same decimal place. Without a usable u: `fallback` (a text). The runs
   * page shows the service's own texts (GET /api/runs *_text); this is for the live page. */
  function measured(value, u, fallback) {
    if (!isNum(value) || !isNum(u) || !(u > 0)) return fallback;
    const decimals = 1 - Math.floor(Math.log10(u));
    if (decimals > 0) return noNegativeZero(value.toFixed(decimals)) + " ± " + u.toFixed(decimals);
    const step = Math.pow(10, -decimals);
    return noNegativeZero((Math.round(value / step) * step).toFixed(0)) + " ± " + (Math.round(u / step) * step).toFixed(0);
  }

  /* "12.3456 ± 0.0012" of a value and its standard uncertainty (u may be null). */
  function withU(valueText, u, uText) {
    return isNum(u) ? valueText + " ± " + uText : valueText;
  }

  /* ------------------------------------------------------------------ plots */

  /* plot(container, {xLabel, yLabel, series: [{label, stroke}], logY, yRange: [lo, hi], ySplits: [ticks],
   *                  height, group, keepZoom, emptyText})
   * -> {setData(x, ...ys), clear(), u}
   * Width follows the container (ResizeObserver). Drag on the plot zooms x, a
   * double click resets. Plots with the same `group` share the cursor and the x zoom.
   * keepZoom: new data keeps a zoom the user made (for the FRF building up). */
  const groups = new Map(); // group name -> Set of plot objects

  function decadesOnly(u, splits) {
    return splits.map((v) => (v > 0 && Math.abs(Math.log10(v) - Math.round(Math.log10(v))) < 1e-9 ? v : null));
  }

  function plot(container, options) {
    const o = Object.assign({ height: 230, series: [], keepZoom: false, emptyText: "no data yet" }, options);
    const height = o.height;
    container.classList.add("plot");
    container.dataset.emptyText = o.emptyText;

    let data = [[], ...o.series.map(() => [])];
    let zoom = null; // [min, max] the user zoomed to, or null
    let updating = false; // inside setData: scale changes are ours, not the user's
    let full = null; // [min, max] of the x data

    const self = { u: null, group: o.group || null };

    function width() {
      return Math.max(200, Math.floor(container.clientWidth || 600));
    }

    const valueFmt = (u, v) => (v === null || v === undefined ? DASH : fmt.sig(v, 4));

    const yScale = { auto: true };
    if (o.logY) Object.assign(yScale, { distr: 3, log: 10 });
    if (o.yRange) Object.assign(yScale, { auto: false, range: o.yRange });

    const opts = {
      width: width(),
      height,
      scales: { x: { time: false }, y: yScale },
      legend: { show: true, live: true },
      cursor: {
        drag: { x: true, y: false, setScale: true },
        sync: o.group ? { key: o.group } : undefined,
      },
      axes: [
        { label: o.xLabel || "", labelSize: 20, size: 40, grid: { stroke: "#e4e7eb" }, ticks: { stroke: "#d0d4d9" } },
        {
          label: o.yLabel || "",
          labelSize: 20,
          size: 64,
          // on a log scale: grid lines at the decades only, small ticks between
          grid: o.logY ? { stroke: "#e4e7eb", filter: decadesOnly } : { stroke: "#e4e7eb" },
          ticks: o.logY ? { stroke: "#d0d4d9", size: 5 } : { stroke: "#d0d4d9" },
          values: (u, splits) => splits.map((v) => (v === null || v === undefined ? "" : fmt.sig(v, 3))),
          // fixed ticks where the caller gives them (a phase reads at -180, -90, 0, 90, 180)
          splits: o.ySplits ? () => o.ySplits : undefined,
        },
      ],
      series: [
        { label: o.xLabel || "x", value: valueFmt },
        ...o.series.map((s) => ({
          label: s.label,
          stroke: s.stroke || "#1f5fbf",
          width: s.width || 1.5,
          dash: s.dash || undefined,
          points: { show: false },
          spanGaps: false,
          value: valueFmt,
        })),
      ],
      hooks: {
        setScale: [
          (u, key) => {
            if (key !== "x" || updating) return;
            const { min, max } = u.scales.x;
            zoom = full && min <= full[0] && max >= full[1] ? null : [min, max];
            if (self.group) {
              for (const other of groups.get(self.group) || []) {
                if (other !== self) other.followZoom(min, max, zoom !== null);
              }
            }
          },
        ],
      },
    };

    self.u = new uPlot(opts, data, container);

    function range(x) {
      let lo = Infinity;
      let hi = -Infinity;
      for (const v of x) {
        if (v < lo) lo = v;
        if (v > hi) hi = v;
      }
      return lo <= hi ? [lo, hi] : null;
    }

    /* setData(x, y1, y2, ...): arrays of numbers; on a log scale values <= 0 become gaps. */
    self.setData = function (x, ...ys) {
      const clean = ys.map((y) =>
        Array.from(y || [], (v) => (isNum(v) && (!o.logY || v > 0) ? v : null))
      );
      data = [Array.from(x || []), ...clean];
      full = range(data[0]);
      container.classList.toggle("empty", data[0].length === 0);
      updating = true;
      try {
        const keep = o.keepZoom && zoom && full && zoom[1] > full[0] && zoom[0] < full[1];
        self.u.setData(data, !keep);
        if (keep) self.u.setScale("x", { min: zoom[0], max: zoom[1] });
        else zoom = null;
      } finally {
        updating = false;
      }
    };

    self.clear = function () {
      self.setData([], ...o.series.map(() => []));
    };

    /* the x zoom of another plot of the group */
    self.followZoom = function (min, max, zoomed) {
      if (!full) return;
      updating = true;
      try {
        if (zoomed) {
          zoom = [min, max];
          self.u.setScale("x", { min, max });
        } else {
          zoom = null;
          self.u.setScale("x", { min: full[0], max: full[1] });
        }
      } finally {
        updating = false;
      }
    };

    if (self.group) {
      if (!groups.has(self.group)) groups.set(self.group, new Set());
      groups.get(self.group).add(self);
    }

    let lastWidth = opts.width;
    const observer = new ResizeObserver(() => {
      const w = width();
      if (w !== lastWidth) {
        lastWidth = w;
        self.u.setSize({ width: w, height });
      }
    });
    observer.observe(container);

    container.classList.add("empty");
    container.daqPlot = self; // for tests and the console: el.daqPlot.u.scales.x
    return self;
  }

  /* ----------------------------------------------------------------- start */

  document.addEventListener("DOMContentLoaded", wireTokenPanel);

  window.DAQ = {
    getToken,
    setToken,
    withToken,
    onToken(fn) {
      tokenListeners.push(fn);
    },
    api,
    ApiError,
    showError,
    clearError,
    showTokenPanel,
    events,
    fmt,
    el,
    $,
    plot,
    analysisCautions,
    cautionLines,
    bandText,
    synthesisText,
    withU,
    measured,
  };
})();
