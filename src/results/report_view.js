// The report's 3-D view (io/report.cpp inlines this file): the compensated points coloured by deviation, status,
// uncertainty or a chosen characteristic's deviation in its frame and zone, over the registered nominal faces'
// outlines, drawn with a depth buffer on a 2-D canvas (no WebGL, no library: it opens offline and in any browser).
// Drag to rotate, shift-drag or right-drag to pan, wheel to zoom, double-click to reset; hovering a point names its
// row.
(function () {
  "use strict";
  const data = JSON.parse(document.getElementById("view-data").textContent);
  const canvas = document.getElementById("view");
  const ctx = canvas.getContext("2d");
  const layer = document.createElement("canvas");  // the points, over the faint outlines
  const info = document.getElementById("view-info");
  const n = data.s.length;

  // Diverging map for deviation (ColorBrewer RdBu, blue inside the material, red outside); beyond the colour bar's
  // range the darkest ends, so out-of-range points stand out. Sequential map for u (viridis).
  const RDBU = [[33, 102, 172], [67, 147, 195], [146, 197, 222], [209, 229, 240], [247, 247, 247],
                [253, 219, 199], [244, 165, 130], [214, 96, 77], [178, 24, 43]];
  const BELOW = [5, 48, 97], ABOVE = [103, 0, 31], NONE = [170, 170, 170];
  const VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  const STATUS = [[26, 152, 80], [215, 48, 39], [244, 109, 67], [117, 112, 179], [253, 174, 97], [120, 120, 120],
                  [0, 0, 0]];

  function ramp(stops, t) {
    const x = Math.min(Math.max(t, 0), 1) * (stops.length - 1);
    const i = Math.min(Math.floor(x), stops.length - 2), f = x - i;
    return [0, 1, 2].map((c) => Math.round(stops[i][c] + f * (stops[i + 1][c] - stops[i][c])));
  }
  const css = (c) => "rgb(" + c[0] + "," + c[1] + "," + c[2] + ")";

  let mode = "deviation";
  // The chosen characteristic, and each drawn point's place in its arrays (-1: not one of its points).
  let chosen = null;
  const onChosen = new Int32Array(n);
  function choose(i) {
    chosen = data.characteristics[i] || null;
    onChosen.fill(-1);
    if (chosen) chosen.k.forEach((k, j) => { onChosen[k] = j; });
  }
  function colour(k) {
    if (mode === "status") return STATUS[data.s[k]] || NONE;
    if (mode === "characteristic") {
      // Its zone's limits at the colour bar's ends.
      const j = chosen ? onChosen[k] : -1;
      return j < 0 ? NONE : diverging(chosen.d[j], chosen.zone);
    }
    if (mode === "u") return data.u[k] === null ? NONE : ramp(VIRIDIS, data.u[k] / data.u_max);
    return data.d[k] === null || data.s[k] !== 0 ? NONE : diverging(data.d[k], data.dev_range);
  }
  // A deviation on the diverging map from lo to hi; beyond them the darkest ends.
  function diverging(d, [lo, hi]) {
    if (d < lo) return BELOW;
    if (d > hi) return ABOVE;
    return ramp(RDBU, (d - lo) / (hi - lo));
  }

  // The view: a turn about z (yaw), then a tilt about the screen's x axis (pitch); orthographic, about the middle of
  // the box holding the points and the outlines, every one of them in sight at the start.
  const low = [Infinity, Infinity, Infinity], high = [-Infinity, -Infinity, -Infinity];
  const grow = (a, k) => {
    for (let c = 0; c < 3; ++c) {
      low[c] = Math.min(low[c], a[k + c]);
      high[c] = Math.max(high[c], a[k + c]);
    }
  };
  for (let k = 0; k < 3 * n; k += 3) grow(data.p, k);
  for (const line of data.lines) for (let k = 0; k < line.length; k += 3) grow(line, k);
  const mid = low.map((v, c) => (isFinite(v) ? (v + high[c]) / 2 : 0));
  const radius = isFinite(low[0]) ? Math.max(Math.hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]) / 2, 1e-9) : 1;
  const home = { yaw: -0.6, pitch: 0.75, zoom: 1, panX: 0, panY: 0 };
  let view = Object.assign({}, home);
  const sx = new Float32Array(n), sy = new Float32Array(n);  // each point's place on screen, for hovering

  function projector() {
    const cy = Math.cos(view.yaw), syw = Math.sin(view.yaw), cp = Math.cos(view.pitch), sp = Math.sin(view.pitch);
    const scale = 0.48 * Math.min(canvas.width, canvas.height) * view.zoom / radius;
    const cx0 = canvas.width / 2 + view.panX, cy0 = canvas.height / 2 + view.panY;
    return function (x, y, z) {
      x -= mid[0];
      y -= mid[1];
      z -= mid[2];
      const x1 = cy * x - syw * y, y1 = syw * x + cy * y;
      return [cx0 + scale * x1, cy0 - scale * (sp * y1 + cp * z), cp * y1 - sp * z];  // screen x, y, depth
    };
  }

  function draw() {
    const W = canvas.width, H = canvas.height;
    const project = projector();
    ctx.fillStyle = "#fff";
    ctx.fillRect(0, 0, W, H);
    // The nominal faces, faint.
    ctx.strokeStyle = "rgba(90,90,90,0.35)";
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (const line of data.lines) {
      for (let k = 0; k < line.length; k += 3) {
        const q = project(line[k], line[k + 1], line[k + 2]);
        if (k === 0) ctx.moveTo(q[0], q[1]); else ctx.lineTo(q[0], q[1]);
      }
    }
    ctx.stroke();
    // The points: squares into a depth buffer, the nearest wins.
    layer.width = W;
    layer.height = H;
    const lctx = layer.getContext("2d");
    const image = lctx.createImageData(W, H);
    const px = image.data, depth = new Float32Array(W * H).fill(Infinity);
    const size = n > 40000 ? 2 : 3;
    for (let k = 0; k < n; ++k) {
      const q = project(data.p[3 * k], data.p[3 * k + 1], data.p[3 * k + 2]);
      sx[k] = q[0];
      sy[k] = q[1];
      const c = colour(k);
      const x0 = Math.round(q[0]) - (size >> 1), y0 = Math.round(q[1]) - (size >> 1);
      for (let y = Math.max(y0, 0); y < Math.min(y0 + size, H); ++y) {
        for (let x = Math.max(x0, 0); x < Math.min(x0 + size, W); ++x) {
          const at = y * W + x;
          if (q[2] >= depth[at]) continue;
          depth[at] = q[2];
          px[4 * at] = c[0];
          px[4 * at + 1] = c[1];
          px[4 * at + 2] = c[2];
          px[4 * at + 3] = 255;
        }
      }
    }
    lctx.putImageData(image, 0, 0);
    ctx.drawImage(layer, 0, 0);
    // The worst points, labelled with their deviation: each label at the first place up and to the right of its
    // point that no earlier label covers, joined to it by a leader.
    ctx.font = "12px sans-serif";
    ctx.lineWidth = 1;
    const placed = [];
    const overlaps = (a) => placed.some((b) => a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h);
    for (const k of data.worst) {
      const x = sx[k], y = sy[k], text = (data.d[k] > 0 ? "+" : "") + data.d[k].toFixed(1) + " \u00b5m";
      const w = ctx.measureText(text).width + 6;
      let box = null;
      for (let step = 0; step < 40 && !box; ++step) {
        const ring = 1 + (step >> 3), dir = step & 7, angle = -Math.PI / 4 + dir * Math.PI / 4;
        const cand = { x: x + 10 + 22 * ring * Math.cos(angle), y: y - 8 - 22 * ring * Math.sin(angle), w: w, h: 16 };
        if (dir > 2 && dir < 6) cand.x -= w + 20;  // labels to the left of the point end short of it
        if (!overlaps(cand)) box = cand;
      }
      if (!box) box = { x: x + 14, y: y - 28, w: w, h: 16 };
      placed.push(box);
      ctx.strokeStyle = "#222";
      ctx.beginPath();
      ctx.arc(x, y, 5, 0, 2 * Math.PI);
      const ax = Math.min(Math.max(x, box.x), box.x + box.w), ay = Math.min(Math.max(y, box.y), box.y + box.h);
      ctx.moveTo(x, y);
      ctx.lineTo(ax, ay);
      ctx.stroke();
      ctx.fillStyle = "rgba(255,255,255,0.85)";
      ctx.fillRect(box.x, box.y, box.w, box.h);
      ctx.strokeRect(box.x, box.y, box.w, box.h);
      ctx.fillStyle = "#111";
      ctx.fillText(text, box.x + 3, box.y + 12);
    }
    legend();
  }

  // The colour bar (or the statuses' key) at the right.
  function legend() {
    const x = canvas.width - 70, top = 40, height = Math.min(260, canvas.height - 80);
    ctx.font = "12px sans-serif";
    ctx.fillStyle = "#111";
    if (mode === "status") {
      data.statuses.forEach((name, i) => {
        ctx.fillStyle = css(STATUS[i]);
        ctx.fillRect(x - 60, top + 20 * i, 14, 14);
        ctx.fillStyle = "#111";
        ctx.fillText(name + " (" + data.status_counts[i] + ")", x - 40, top + 20 * i + 12);
      });
      return;
    }
    const [lo, hi] = mode === "u" ? [0, data.u_max] : mode === "characteristic" && chosen ? chosen.zone : data.dev_range;
    for (let y = 0; y < height; ++y) {
      const t = 1 - y / (height - 1);
      ctx.fillStyle = css(mode === "u" ? ramp(VIRIDIS, t) : ramp(RDBU, t));
      ctx.fillRect(x, top + y, 18, 1);
    }
    ctx.strokeStyle = "#444";
    ctx.strokeRect(x, top, 18, height);
    ctx.fillStyle = "#111";
    const title = mode === "u" ? "u (\u00b5m)" : mode === "characteristic" && chosen ? chosen.name + ": zone (\u00b5m)"
                                                                                   : "deviation (\u00b5m)";
    ctx.fillText(title, x - 40, top - 12);
    for (let i = 0; i <= 4; ++i) {
      const v = lo + (hi - lo) * (1 - i / 4);
      ctx.fillText(v.toFixed(hi - lo < 4 ? 2 : 1), x + 24, top + (height - 1) * i / 4 + 4);
    }
    if (mode === "deviation" || mode === "characteristic") {
      ctx.fillStyle = css(ABOVE);
      ctx.fillRect(x, top - 8, 18, 6);
      ctx.fillStyle = css(BELOW);
      ctx.fillRect(x, top + height + 2, 18, 6);
      ctx.fillStyle = css(NONE);
      ctx.fillRect(x, top + height + 16, 18, 10);
      ctx.fillStyle = "#111";
      ctx.fillText(mode === "deviation" ? "not ok" : "not judged", x + 24, top + height + 25);
    }
  }

  function resize() {
    const width = Math.max(320, Math.min(canvas.parentElement.clientWidth, 1400));
    canvas.width = width;
    canvas.height = Math.round(width * 0.6);
    draw();
  }

  // Redraws asked for by interaction, one for a burst of events (100 000 points take tens of milliseconds to draw):
  // a timer, not an animation frame, so that a page in the background or a headless browser redraws as well.
  let pending = false;
  function redraw() {
    if (pending) return;
    pending = true;
    setTimeout(() => {
      pending = false;
      draw();
    }, 0);
  }

  // Pointer events: a mouse, a pen or a finger on a shop-floor tablet alike.
  let drag = null;
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("pointerdown", (e) => {
    drag = { x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button === 2 };
    try {
      canvas.setPointerCapture(e.pointerId);  // keeps the drag when the pointer leaves the canvas
    } catch (err) {
      // a pointer that is already gone: the drag still works while it stays on the canvas
    }
  });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("pointercancel", () => { drag = null; });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.pan) {
      view.panX += dx;
      view.panY += dy;
    } else {
      view.yaw += dx * 0.01;
      view.pitch = Math.max(-Math.PI / 2, Math.min(Math.PI / 2, view.pitch + dy * 0.01));
    }
    redraw();
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    view.zoom *= Math.exp(-e.deltaY * 0.001);
    redraw();
  }, { passive: false });
  canvas.addEventListener("dblclick", () => {
    view = Object.assign({}, home);
    draw();
  });
  canvas.addEventListener("pointermove", (e) => {
    if (drag) return;
    const box = canvas.getBoundingClientRect();
    const x = (e.clientX - box.left) * canvas.width / box.width, y = (e.clientY - box.top) * canvas.height / box.height;
    let best = -1, bestD = 36;  // within 6 pixels (squared)
    for (let k = 0; k < n; ++k) {
      const d = (sx[k] - x) * (sx[k] - x) + (sy[k] - y) * (sy[k] - y);
      if (d < bestD) { bestD = d; best = k; }
    }
    info.textContent = best < 0 ? "\u00a0" :
      "row " + data.row[best] + ": " + data.statuses[data.s[best]] +
      (data.d[best] === null ? "" : ", deviation " + data.d[best].toFixed(2) + " \u00b5m") +
      (data.u[best] === null ? "" : ", u " + data.u[best].toFixed(2) + " \u00b5m") +
      (mode === "characteristic" && chosen && onChosen[best] >= 0
        ? "; " + chosen.name + ": " + chosen.d[onChosen[best]].toFixed(2) + " \u00b1 " + chosen.U[onChosen[best]].toFixed(2) +
          " \u00b5m in its frame"
        : "");
  });
  for (const input of document.querySelectorAll("input[name=colour]")) {
    input.addEventListener("change", () => {
      mode = input.value;
      draw();
    });
  }
  const select = document.getElementById("view-characteristic");
  if (select) {
    choose(Number(select.value));
    select.addEventListener("change", () => {
      choose(Number(select.value));
      if (mode === "characteristic") draw();
    });
  }
  window.addEventListener("resize", resize);
  resize();
  document.body.dataset.drawnPoints = String(n);  // for the tests: the view has drawn
})();
