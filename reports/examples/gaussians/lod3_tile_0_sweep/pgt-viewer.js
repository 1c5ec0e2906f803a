// pgt report viewer (docs/design.md §5 "Interactive where a browser runs it"): reference,
// approximation and error panes with synchronised zoom and pan (nearest-neighbour pixels), an
// A/B flip, an exposure control and a pixel probe. Reads window.PGT_DATA (pgt-data.js, written
// by src/report/viewer.rs); without it, or without JavaScript, the page keeps its static images.
(function () {
  "use strict";
  var D = window.PGT_DATA;
  var root = document.getElementById("pgt-viewer");
  if (!D || !root) { return; }
  var W = D.width, H = D.height;
  var MAX_PANE = 360; // CSS pixels of a pane's longer side
  var ZOOM_STEP = 1.25, ZOOM_MIN = 1, ZOOM_MAX = 256;

  // IEEE binary16 → number.
  function half(h) {
    var s = (h & 0x8000) ? -1 : 1, e = (h >> 10) & 0x1f, m = h & 0x3ff;
    if (e === 0) { return s * m * Math.pow(2, -24); }
    if (e === 31) { return m ? NaN : s * Infinity; }
    return s * (1 + m / 1024) * Math.pow(2, e - 15);
  }

  // base64 of little-endian floats → Float32Array (R, G, B interleaved, row-major from the top).
  function decode(b64) {
    if (!b64) { return null; }
    var bin = atob(b64), n = bin.length, bytes = new Uint8Array(n), i;
    for (i = 0; i < n; i++) { bytes[i] = bin.charCodeAt(i); }
    var dv = new DataView(bytes.buffer), f16 = D.encoding === "f16";
    var out = new Float32Array(f16 ? n / 2 : n / 4);
    for (i = 0; i < out.length; i++) {
      out[i] = f16 ? half(dv.getUint16(2 * i, true)) : dv.getFloat32(4 * i, true);
    }
    return out;
  }

  var reference = { label: "reference", png: D.reference.png, data: decode(D.reference.data) };
  var estimate = decode(D.estimate);
  var runs = D.approximations.map(function (a) {
    return { label: a.label, png: a.png, heatmap: a.heatmap, data: decode(a.data) };
  });
  var hasData = !!reference.data && runs.every(function (r) { return !!r.data; });
  var state = { run: 0, flipped: false, exposure: D.exposure, zoom: 1, tx: 0, ty: 0, pixel: null };

  var ids = ["a", "b", "e"];
  var panes = {};
  ids.forEach(function (id) {
    var canvas = document.getElementById("pgt-canvas-" + id);
    canvas.width = W;
    canvas.height = H;
    panes[id] = {
      canvas: canvas,
      viewport: document.getElementById("pgt-viewport-" + id),
      title: document.getElementById("pgt-title-" + id)
    };
  });
  // Panes keep the image's aspect ratio, the longer side MAX_PANE CSS pixels.
  var fit = MAX_PANE / Math.max(W, H);
  ids.forEach(function (id) {
    panes[id].viewport.style.width = Math.round(W * fit) + "px";
    panes[id].viewport.style.height = Math.round(H * fit) + "px";
  });

  function srgb8(v) {
    if (!(v > 0)) { return 0; }
    if (v >= 1) { return 255; }
    var s = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    return Math.floor(s * 255 + 0.5);
  }

  function drawValues(canvas, data) {
    var ctx = canvas.getContext("2d"), img = ctx.createImageData(W, H), p = img.data;
    var k = Math.pow(2, state.exposure);
    for (var i = 0, n = W * H; i < n; i++) {
      p[4 * i] = srgb8(data[3 * i] * k);
      p[4 * i + 1] = srgb8(data[3 * i + 1] * k);
      p[4 * i + 2] = srgb8(data[3 * i + 2] * k);
      p[4 * i + 3] = 255;
    }
    ctx.putImageData(img, 0, 0);
  }

  function drawPng(canvas, src) {
    var img = new Image();
    img.onload = function () {
      canvas.getContext("2d").drawImage(img, 0, 0, W, H);
      canvas.setAttribute("data-drawn", src);
    };
    img.src = src;
  }

  function draw(id, item) {
    if (item.data) { drawValues(panes[id].canvas, item.data); } else { drawPng(panes[id].canvas, item.png); }
  }

  function drawAll() {
    var run = runs[state.run];
    var a = state.flipped ? run : reference, b = state.flipped ? reference : run;
    draw("a", a);
    draw("b", b);
    drawPng(panes.e.canvas, run.heatmap);
    panes.a.title.textContent = (state.flipped ? "B: " : "A: ") + a.label;
    panes.b.title.textContent = (state.flipped ? "A: " : "B: ") + b.label;
    root.setAttribute("data-flipped", state.flipped ? "1" : "0");
  }

  function applyTransform() {
    var s = fit * state.zoom;
    ids.forEach(function (id) {
      panes[id].canvas.style.transform =
        "translate(" + state.tx + "px," + state.ty + "px) scale(" + s + ")";
    });
    document.getElementById("pgt-zoom-value").textContent =
      "zoom " + (Math.round(state.zoom * 100) / 100) + "×";
    root.setAttribute("data-zoom", String(state.zoom));
  }

  // Zoom by `factor` keeping the image point under (mx, my) (CSS pixels in a pane) in place.
  function zoomAt(factor, mx, my) {
    var z = Math.min(ZOOM_MAX, Math.max(ZOOM_MIN, state.zoom * factor));
    var r = z / state.zoom;
    state.tx = mx - (mx - state.tx) * r;
    state.ty = my - (my - state.ty) * r;
    state.zoom = z;
    if (z === ZOOM_MIN) { state.tx = 0; state.ty = 0; }
    applyTransform();
  }

  function zoomCentre(factor) { zoomAt(factor, W * fit / 2, H * fit / 2); }

  function flip() { state.flipped = !state.flipped; drawAll(); showProbe(); }

  function fmt(v) { return isFinite(v) ? Number(v).toPrecision(6) : String(v); }

  function setCells(key, values) {
    for (var c = 0; c < 3; c++) {
      var td = root.querySelector('td[data-probe="' + key + "-" + c + '"]');
      td.textContent = values ? fmt(values[c]) : "—";
    }
  }

  function showProbe() {
    var p = state.pixel;
    if (!p || !hasData) { return; }
    var i = 3 * (p.y * W + p.x), run = runs[state.run];
    var r = [0, 1, 2].map(function (c) { return reference.data[i + c]; });
    var a = [0, 1, 2].map(function (c) { return run.data[i + c]; });
    setCells("reference", r);
    setCells("approximation", a);
    setCells("difference", [0, 1, 2].map(function (c) { return Math.abs(a[c] - r[c]); }));
    setCells("estimate", estimate ? [0, 1, 2].map(function (c) { return estimate[i + c]; }) : null);
    document.getElementById("pgt-probe-pixel").textContent = "pixel (" + p.x + ", " + p.y + ")";
    var table = document.getElementById("pgt-probe");
    table.setAttribute("data-x", String(p.x));
    table.setAttribute("data-y", String(p.y));
  }

  // The image pixel under a pointer event, from the transformed canvas's box.
  function pixelAt(ev, id) {
    var box = panes[id].canvas.getBoundingClientRect();
    var x = Math.floor((ev.clientX - box.left) / box.width * W);
    var y = Math.floor((ev.clientY - box.top) / box.height * H);
    return x >= 0 && y >= 0 && x < W && y < H ? { x: x, y: y } : null;
  }

  var drag = null;
  ids.forEach(function (id) {
    var vp = panes[id].viewport;
    vp.addEventListener("wheel", function (ev) {
      ev.preventDefault();
      var box = vp.getBoundingClientRect();
      zoomAt(ev.deltaY < 0 ? ZOOM_STEP : 1 / ZOOM_STEP,
        ev.clientX - box.left - vp.clientLeft, ev.clientY - box.top - vp.clientTop);
    }, { passive: false });
    vp.addEventListener("pointerdown", function (ev) {
      drag = { x: ev.clientX, y: ev.clientY, tx: state.tx, ty: state.ty };
      vp.setPointerCapture(ev.pointerId);
    });
    vp.addEventListener("pointerup", function () { drag = null; });
    vp.addEventListener("pointermove", function (ev) {
      if (drag && state.zoom > ZOOM_MIN) {
        state.tx = drag.tx + ev.clientX - drag.x;
        state.ty = drag.ty + ev.clientY - drag.y;
        applyTransform();
        return;
      }
      var p = pixelAt(ev, id);
      if (p) { state.pixel = p; showProbe(); }
    });
  });

  document.getElementById("pgt-flip").addEventListener("click", flip);
  document.getElementById("pgt-zoom-in").addEventListener("click", function () { zoomCentre(ZOOM_STEP * ZOOM_STEP); });
  document.getElementById("pgt-zoom-out").addEventListener("click", function () { zoomCentre(1 / (ZOOM_STEP * ZOOM_STEP)); });
  document.getElementById("pgt-zoom-fit").addEventListener("click", function () { zoomAt(0, 0, 0); });
  document.addEventListener("keydown", function (ev) {
    var tag = ev.target && ev.target.tagName;
    if (tag === "INPUT" || tag === "SELECT" || tag === "TEXTAREA" || ev.ctrlKey || ev.metaKey || ev.altKey) { return; }
    if (ev.key === "f" || ev.key === "F") { flip(); } else if (ev.key === "+" || ev.key === "=") {
      zoomCentre(ZOOM_STEP * ZOOM_STEP);
    } else if (ev.key === "-") { zoomCentre(1 / (ZOOM_STEP * ZOOM_STEP)); } else if (ev.key === "0") {
      zoomAt(0, 0, 0);
    } else { return; }
    ev.preventDefault();
  });

  var exposure = document.getElementById("pgt-exposure");
  var exposureOut = document.getElementById("pgt-exposure-value");
  exposure.value = String(state.exposure);
  exposureOut.textContent = String(Math.round(state.exposure * 100) / 100);
  exposure.disabled = !hasData;
  exposure.addEventListener("input", function () {
    state.exposure = Number(exposure.value);
    exposureOut.textContent = String(Math.round(state.exposure * 100) / 100);
    drawAll();
  });
  var select = document.getElementById("pgt-run");
  if (select) {
    select.addEventListener("change", function () { state.run = Number(select.value); drawAll(); showProbe(); });
  }
  if (!hasData) { document.getElementById("pgt-probe").hidden = true; }
  document.getElementById("pgt-viewer-note").textContent = D.note || "";

  drawAll();
  applyTransform();
  root.hidden = false;
  // For tests and the console: the viewer's state.
  window.pgtViewer = { state: state, fit: fit, width: W, height: H };
  root.setAttribute("data-ready", "1");
}());
