// trace.html's script (sil-host/src/trace_page): draws the arm on the belt at one
// frame of the embedded trace and the trace's plots with a cursor at that time.
// No library, no network: everything comes from the JSON in #trace-data.
"use strict";
(function () {
  const D = JSON.parse(document.getElementById("trace-data").textContent);
  const F = D.frames;
  const N = F.t.length;
  const $ = (id) => document.getElementById(id);
  const ok = (v) => typeof v === "number" && isFinite(v);
  const fmt = (v, d) => (ok(v) ? v.toFixed(d) : "\u2013");
  const FONT = '"DejaVu Sans", "Helvetica Neue", Arial, sans-serif';
  const C = {
    link: "#4a4a4a", tip: "#ff00ff", base: "#00ffff", force: "#d55e00", belt: "#d9d9d9",
    beltLine: "#505050", stripe: "#9c9c9c", ref: "#6e6e6e", trail: "#e3b0e3", text: "#1a1a1a",
    grid: "#ebebeb", frame: "#8c8c8c", cursor: "#d55e00",
  };

  // ---- the header, the notes ----
  $("title").textContent = D.title;
  D.facts.forEach(([k, v], i) => {
    if (i) $("facts").append(" \u00b7 ");
    const b = document.createElement("b");
    b.textContent = k + ": ";
    $("facts").append(b, v);
  });
  D.notes.forEach((n) => {
    const li = document.createElement("li");
    li.textContent = n;
    $("notes").append(li);
  });
  $("generator").textContent = "Written by " + D.generator + "; every number is in this file (no network).";

  // ---- the events: instants, between the frames and the plots' samples ----
  const E = D.events;
  const NE = E.t.length;
  const EV_COLOR = {
    touchdown: "#0072b2", lift_off: "#009e73", safe_state: "#d55e00", impact_without_collision: "#cc79a7",
    p_zero: "#cc79a7", jam: "#cc79a7", singular_point: "#cc79a7", bridge: "#cc79a7",
  };
  const evKind = (j) => E.kinds[E.kind[j]];
  const evColor = (j) => EV_COLOR[evKind(j)] || "#8c8c8c";
  // An impact: an impulse on the contact (a touchdown, an impact without collision, a jam's).
  const isImpact = (j) => E.p_n[j] !== 0 || E.p_t[j] !== 0 || evKind(j) === "touchdown";
  // The index of the first event after time t.
  function firstAfter(t) {
    let a = 0, b = NE;
    while (a < b) {
      const m = (a + b) >> 1;
      if (E.t[m] <= t) a = m + 1;
      else b = m;
    }
    return a;
  }
  // The events in (ta, tb].
  function between(ta, tb) {
    const out = [];
    for (let j = firstAfter(ta); j < NE && E.t[j] <= tb; j++) out.push(j);
    return out;
  }
  const evText = (j) => {
    let s = evKind(j) + " at " + E.t[j].toFixed(5) + " s";
    if (E.p_n[j] !== 0 || E.p_t[j] !== 0) s += " (P\u2099 " + E.p_n[j].toPrecision(3) + ", P\u209c " + E.p_t[j].toPrecision(3) + " N s)";
    return s;
  };
  if (N === 0) {
    $("readout").textContent = "The run has no samples: nothing to show.";
    return;
  }

  // A canvas at its CSS size, drawn in CSS px whatever the device pixel ratio.
  function setup(c) {
    const dpr = window.devicePixelRatio || 1;
    const w = c.clientWidth || c.width, h = c.clientHeight || c.height;
    c.width = Math.round(w * dpr);
    c.height = Math.round(h * dpr);
    const ctx = c.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    return { ctx, w, h, dpr };
  }

  // ---- the arm view: world (z_t, z_n) in m to canvas px, one scale both ways ----
  const arm = $("arm");
  const A = setup(arm);
  const [x0, x1, y0, y1] = D.view;
  const PAD = 12, LEGEND = 44;
  const s = Math.min((A.w - 2 * PAD) / (x1 - x0), (A.h - 2 * PAD - LEGEND) / (y1 - y0));
  const ox = PAD + (A.w - 2 * PAD - s * (x1 - x0)) / 2 - s * x0;
  const oy = PAD + s * y1;
  const px = (x, y) => [ox + s * x, oy - s * y];
  function publishMapping() {
    const r = arm.getBoundingClientRect();
    arm.dataset.pxPerM = String(s);
    arm.dataset.baseX = String(r.left + window.scrollX + ox);
    arm.dataset.baseY = String(r.top + window.scrollY + oy);
  }

  function arrow(c, xa, ya, xb, yb, head) {
    const a = Math.atan2(yb - ya, xb - xa);
    c.beginPath();
    c.moveTo(xa, ya);
    c.lineTo(xb - 0.8 * head * Math.cos(a), yb - 0.8 * head * Math.sin(a));
    c.stroke();
    c.beginPath();
    c.moveTo(xb, yb);
    c.lineTo(xb - head * Math.cos(a - 0.4), yb - head * Math.sin(a - 0.4));
    c.lineTo(xb - head * Math.cos(a + 0.4), yb - head * Math.sin(a + 0.4));
    c.closePath();
    c.fill();
  }

  function disc(c, x, y, r, fill, stroke) {
    c.beginPath();
    c.arc(x, y, r, 0, 2 * Math.PI);
    c.fillStyle = fill;
    c.fill();
    if (stroke) {
      c.strokeStyle = stroke;
      c.lineWidth = 1.5;
      c.stroke();
    }
  }

  // A polyline through `pts` ([[x, y], ...], px) in the current stroke style.
  function polyline(c, pts) {
    c.beginPath();
    pts.forEach(([x, y], k) => (k ? c.lineTo(x, y) : c.moveTo(x, y)));
    c.stroke();
  }

  function drawArm(i) {
    const c = A.ctx, t = F.t[i];
    c.fillStyle = "#fff";
    c.fillRect(0, 0, A.w, A.h);
    c.font = "13px " + FONT;
    // The belt: a band under its surface z_n = -H, stripes every 2 cm moving at v_belt.
    const [bl, bt] = px(x0, -D.h), [br, bb] = px(x1, -D.h - D.belt_depth);
    c.fillStyle = C.belt;
    c.fillRect(bl, bt, br - bl, bb - bt);
    const gap = 0.02, shift = (((D.v_belt * t) % gap) + gap) % gap;
    c.save();
    c.beginPath();
    c.rect(bl, bt, br - bl, bb - bt);
    c.clip();
    c.strokeStyle = C.stripe;
    c.lineWidth = 2;
    for (let k = Math.floor((x0 - shift) / gap) - 2; k * gap + shift < x1 + D.belt_depth; k++) {
      const x = k * gap + shift;
      polyline(c, [px(x, -D.h), px(x - D.belt_depth, -D.h - D.belt_depth)]);
    }
    c.restore();
    c.strokeStyle = C.beltLine;
    c.lineWidth = 1.5;
    polyline(c, [[bl, bt], [br, bt]]);
    // The base mount, hatched above the base joint.
    const [ml, mt] = px(-0.04, 0.025), [mr] = px(0.04, 0);
    c.strokeStyle = C.beltLine;
    c.lineWidth = 1;
    c.beginPath();
    c.moveTo(ml, oy);
    c.lineTo(mr, oy);
    for (let x = ml; x < mr; x += 6) {
      c.moveTo(x, oy);
      c.lineTo(x + 6, mt);
    }
    c.stroke();
    // The reference z_t* on the belt (closed loop).
    const ref = F.z_t_ref[i];
    if (ok(ref)) {
      const [rx, ry] = px(ref, -D.h - D.belt_depth);
      c.fillStyle = C.ref;
      c.beginPath();
      c.moveTo(rx, ry + 1);
      c.lineTo(rx - 6, ry + 10);
      c.lineTo(rx + 6, ry + 10);
      c.closePath();
      c.fill();
      c.textBaseline = "top";
      c.fillText("z\u209c*", rx + 9, ry + 2);
      c.textBaseline = "alphabetic";
    }
    // The tip's path over the last 0.3 s.
    c.strokeStyle = C.trail;
    c.lineWidth = 2;
    c.beginPath();
    for (let j = i, first = true; j >= 0 && t - F.t[j] <= 0.3; j--) {
      if (!ok(F.tip_x[j]) || !ok(F.tip_y[j])) break;
      const [x, y] = px(F.tip_x[j], F.tip_y[j]);
      first ? c.moveTo(x, y) : c.lineTo(x, y);
      first = false;
    }
    c.stroke();
    // The links, the elbow, the force arrow, the base joint and the tip on top.
    const ex = F.elbow_x[i], ey = F.elbow_y[i], tx = F.tip_x[i], ty = F.tip_y[i];
    if ([ex, ey, tx, ty].every(ok)) {
      const [pe, qe] = px(ex, ey), [pt, qt] = px(tx, ty);
      c.strokeStyle = C.link;
      c.lineWidth = 7;
      c.lineCap = "round";
      c.lineJoin = "round";
      polyline(c, [[ox, oy], [pe, qe], [pt, qt]]);
      c.lineCap = "butt";
      disc(c, pe, qe, 5, "#fff", C.link);
      const ft = F.f_t[i], fn = F.f_n[i];
      if (ok(ft) && ok(fn) && Math.hypot(ft, fn) * s / D.force_n_per_m > 2) {
        const [fx, fy] = px(tx + ft / D.force_n_per_m, ty + fn / D.force_n_per_m);
        c.strokeStyle = C.force;
        c.fillStyle = C.force;
        c.lineWidth = 3;
        arrow(c, pt, qt, fx, fy, 11);
      }
      disc(c, ox, oy, 5, C.base);
      disc(c, pt, qt, 6, C.tip);
      // An impact since the previous frame: a ring around the contact, its kinds beside it.
      const hits = between(i > 0 ? F.t[i - 1] : -Infinity, t).filter(isImpact);
      if (hits.length) {
        c.strokeStyle = evColor(hits[0]);
        c.lineWidth = 3;
        c.beginPath();
        c.arc(pt, qt, 15, 0, 2 * Math.PI);
        c.stroke();
        c.fillStyle = evColor(hits[0]);
        c.font = "bold 12px " + FONT;
        const names = [...new Set(hits.map(evKind))].join(", ");
        c.fillText((hits.length > 1 ? hits.length + " impacts: " : "impact: ") + names, pt + 19, qt - 12);
      }
    } else {
      disc(c, ox, oy, 5, C.base);
      c.fillStyle = C.force;
      c.fillText("no finite state at this time", PAD, PAD + 30);
    }
    // The time and mode, the legend: scale bar, force scale, belt.
    c.fillStyle = C.text;
    c.font = "bold 14px " + FONT;
    c.fillText("t = " + fmt(t, 3) + " s   " + (D.modes[F.mode[i]] || "?"), PAD, PAD + 10);
    c.font = "13px " + FONT;
    const ly = A.h - LEGEND + 26;
    c.strokeStyle = C.text;
    c.lineWidth = 2;
    polyline(c, [[PAD, ly - 4], [PAD, ly], [PAD + 0.1 * s, ly], [PAD + 0.1 * s, ly - 4]]);
    c.fillText("10 cm", PAD + 0.1 * s + 6, ly + 4);
    let lx = PAD + 0.1 * s + 62;
    c.strokeStyle = C.force;
    c.fillStyle = C.force;
    c.lineWidth = 3;
    arrow(c, lx, ly, lx + 0.01 * s * 3, ly, 9);
    c.fillStyle = C.text;
    c.fillText("contact force, 1 cm = " + +(D.force_n_per_m / 100).toPrecision(3) + " N", lx + 0.03 * s + 6, ly + 4);
    lx += 0.03 * s + 215;
    c.fillText("belt " + (D.v_belt < 0 ? "\u2190 " : "\u2192 ") + Math.abs(D.v_belt) + " m/s", lx, ly + 4);
    publishMapping();
    arm.dataset.frameT = String(t);
  }

  // ---- the plots: static curves drawn once, the cursor over them ----
  const plots = $("plots");
  const G = setup(plots);
  const still = document.createElement("canvas");
  still.width = plots.width;
  still.height = plots.height;
  // MR: room on the right for the impulses' own axis (N s) on the force panel.
  const ML = 74, MR = 58, MT = 18, MB = 42, GAP = 24;
  const tMin = F.t[0], tMax = Math.max(F.t[N - 1], tMin + 1e-9);
  // The plots' time window: the whole run, or a span around the current time.
  let wA = tMin, wB = tMax;
  const xOf = (t) => ML + ((t - wA) / (wB - wA)) * (G.w - ML - MR);
  function setWindow(t) {
    const span = parseFloat($("span").value);
    let a = tMin, b = tMax;
    if (span > 0 && span < tMax - tMin) {
      a = Math.min(Math.max(t - span / 2, tMin), tMax - span);
      b = a + span;
    }
    if (a === wA && b === wB) return false;
    [wA, wB] = [a, b];
    return true;
  }
  const weights = D.panels.map((p) => (p.categories ? 0.55 : 1));
  const unit = (G.h - MT - MB - GAP * (D.panels.length - 1)) / weights.reduce((a, b) => a + b, 0);
  let top = MT;
  const boxes = D.panels.map((p, k) => {
    const b = { top, h: weights[k] * unit };
    top += b.h + GAP;
    return b;
  });
  const niceStep = (span) => {
    const d = Math.pow(10, Math.floor(Math.log10(span)));
    return [1, 2, 5, 10].map((m) => m * d).find((v) => v >= span - 1e-12 * d) || 10 * d;
  };
  const tickText = (v, step) => {
    const d = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
    return (Math.abs(v) < step * 1e-6 ? 0 : v).toFixed(d).replace("-", "\u2212");
  };

  function drawPanel(c, p, b, last) {
    let lo = Infinity, hi = -Infinity;
    if (p.categories) {
      lo = -0.4;
      hi = p.categories.length - 0.6;
    } else {
      const whole = wA <= tMin && wB >= tMax;
      p.series.forEach((sr) => sr.y.forEach((v, j) => {
        if (ok(v) && (whole || (sr.t[j] >= wA && sr.t[j] <= wB))) {
          lo = Math.min(lo, v);
          hi = Math.max(hi, v);
        }
      }));
      if (!(lo <= hi)) [lo, hi] = [-1, 1];
      if (hi - lo < 1e-9) {
        const d = Math.max(Math.abs(lo) * 0.1, 0.01);
        [lo, hi] = [lo - d, hi + d];
      }
      const m = 0.08 * (hi - lo);
      [lo, hi] = [lo - m, hi + m];
    }
    const yOf = (v) => b.top + b.h - ((v - lo) / (hi - lo)) * b.h;
    const right = G.w - MR;
    c.font = "11px " + FONT;
    c.textBaseline = "middle";
    // y ticks and grid
    const ticks = p.categories ? p.categories.map((_, k) => k) : [];
    if (!p.categories) {
      const st = niceStep((hi - lo) / 4);
      for (let v = Math.ceil(lo / st) * st; v <= hi; v += st) ticks.push(v);
      ticks.step = st;
    }
    ticks.forEach((v) => {
      const y = yOf(v);
      c.strokeStyle = C.grid;
      c.lineWidth = 1;
      polyline(c, [[ML, y], [right, y]]);
      c.fillStyle = C.text;
      c.textAlign = "right";
      c.fillText(p.categories ? p.categories[v] : tickText(v, ticks.step), ML - 5, y);
    });
    // x ticks (labels under the last panel)
    const xs = niceStep((wB - wA) / 8);
    c.textAlign = "center";
    c.textBaseline = "top";
    for (let k = Math.ceil(wA / xs - 1e-9); k * xs <= wB + 1e-9 * xs; k++) {
      const t = k * xs;
      const x = xOf(t);
      c.strokeStyle = C.frame;
      polyline(c, [[x, b.top + b.h], [x, b.top + b.h + 4]]);
      if (last) c.fillText(tickText(t, xs), x, b.top + b.h + 6);
    }
    // the curves, clipped to the box
    c.save();
    c.beginPath();
    c.rect(ML, b.top, right - ML, b.h);
    c.clip();
    p.series.forEach((sr) => {
      c.strokeStyle = sr.color;
      c.lineWidth = 1.5;
      c.setLineDash(sr.dash ? [6, 3] : []);
      c.beginPath();
      let prev = null;
      for (let j = 0; j < sr.t.length; j++) {
        const v = sr.y[j];
        if (!ok(v) || !ok(sr.t[j])) {
          prev = null;
          continue;
        }
        const x = xOf(sr.t[j]), y = yOf(v);
        if (prev === null) c.moveTo(x, y);
        else {
          if (sr.step) c.lineTo(x, prev);
          c.lineTo(x, y);
        }
        prev = y;
      }
      c.stroke();
    });
    c.setLineDash([]);
    // The events in the window: a tick on the time axis each, coloured by kind; on
    // the impulse panel the normal impulses as stems, on their own scale.
    const ja = firstAfter(wA - 1e-12), jb = firstAfter(wB);
    const bottom = b.top + b.h;
    const byColor = {};
    for (let j = ja; j < jb; j++) (byColor[evColor(j)] = byColor[evColor(j)] || []).push(j);
    let pMax = 0;
    if (p.impulses) for (let j = ja; j < jb; j++) pMax = Math.max(pMax, Math.abs(E.p_n[j]));
    Object.entries(byColor).forEach(([color, js]) => {
      c.strokeStyle = color;
      c.fillStyle = color;
      c.lineWidth = 1.2;
      c.beginPath();
      js.forEach((j) => {
        const x = xOf(E.t[j]);
        c.moveTo(x, bottom);
        c.lineTo(x, bottom - 7);
        if (pMax > 0 && E.p_n[j] !== 0) {
          c.moveTo(x, bottom);
          c.lineTo(x, bottom - 0.85 * b.h * (Math.abs(E.p_n[j]) / pMax));
        }
      });
      c.stroke();
      if (pMax > 0) js.forEach((j) => E.p_n[j] !== 0 && disc(c, xOf(E.t[j]), bottom - 0.85 * b.h * (Math.abs(E.p_n[j]) / pMax), 2.2, color));
    });
    if (pMax > 0) {
      c.fillStyle = C.text;
      c.font = "11px " + FONT;
      c.textAlign = "left";
      c.textBaseline = "top";
      c.fillText("stems: impulse |P\u2099| of each impact, tallest " + pMax.toPrecision(3) + " N s", ML + 6, b.top + 4);
    }
    c.restore();
    if (pMax > 0) {
      // The stems' own axis, on the right: |P_n| in N s (a stem of pMax reaches 0.85 of the box).
      const pOf = (v) => bottom - 0.85 * b.h * (v / pMax);
      const pst = niceStep(pMax / 0.85 / 3);
      c.strokeStyle = C.frame;
      c.fillStyle = C.text;
      c.font = "11px " + FONT;
      c.textAlign = "left";
      c.textBaseline = "middle";
      for (let k = 0; k * pst <= pMax / 0.85 + 1e-12 * pst; k++) {
        const y = pOf(k * pst);
        polyline(c, [[right, y], [right + 4, y]]);
        c.fillText(tickText(k * pst, pst), right + 6, y);
      }
      c.save();
      c.translate(G.w - 8, b.top + b.h / 2);
      c.rotate(Math.PI / 2);
      c.textAlign = "center";
      c.fillText("|P\u2099| (N s)", 0, 0);
      c.restore();
    }
    c.strokeStyle = C.frame;
    c.lineWidth = 1;
    c.strokeRect(ML, b.top, right - ML, b.h);
    // the y label, turned
    c.save();
    c.translate(14, b.top + b.h / 2);
    c.rotate(-Math.PI / 2);
    c.font = "12px " + FONT;
    c.textAlign = "center";
    c.textBaseline = "middle";
    c.fillStyle = C.text;
    c.fillText(p.label, 0, 0);
    c.restore();
    // the legend, above the box at its right (over no data)
    c.font = "11px " + FONT;
    c.textAlign = "left";
    c.textBaseline = "middle";
    const widths = p.series.map((sr) => 26 + c.measureText(sr.name).width + 12);
    let lx = right - widths.reduce((a, w) => a + w, 0) + 8;
    const ly = b.top - 8;
    p.series.forEach((sr, k) => {
      c.strokeStyle = sr.color;
      c.lineWidth = 2;
      c.setLineDash(sr.dash ? [5, 2] : []);
      polyline(c, [[lx, ly], [lx + 22, ly]]);
      c.setLineDash([]);
      c.fillStyle = C.text;
      c.fillText(sr.name, lx + 26, ly);
      lx += widths[k];
    });
  }

  function drawStill() {
    const c = still.getContext("2d");
    c.setTransform(G.dpr, 0, 0, G.dpr, 0, 0);
    c.fillStyle = "#fff";
    c.fillRect(0, 0, G.w, G.h);
    D.panels.forEach((p, k) => drawPanel(c, p, boxes[k], k === D.panels.length - 1));
    c.font = "12px " + FONT;
    c.textAlign = "center";
    c.textBaseline = "alphabetic";
    c.fillStyle = C.text;
    c.fillText("time t (s)", ML + (G.w - ML - MR) / 2, G.h - 4);
  }

  function drawPlots(i) {
    const c = G.ctx;
    c.setTransform(1, 0, 0, 1, 0, 0);
    c.drawImage(still, 0, 0);
    c.setTransform(G.dpr, 0, 0, G.dpr, 0, 0);
    const x = xOf(F.t[i]);
    c.strokeStyle = C.cursor;
    c.lineWidth = 1.5;
    polyline(c, [[x, MT], [x, boxes[boxes.length - 1].top + boxes[boxes.length - 1].h]]);
  }

  // ---- time: the frame nearest a time, play, the slider, the keys ----
  function nearest(t) {
    let a = 0, b = N - 1;
    while (b - a > 1) {
      const m = (a + b) >> 1;
      if (F.t[m] <= t) a = m;
      else b = m;
    }
    return Math.abs(F.t[b] - t) < Math.abs(t - F.t[a]) ? b : a;
  }
  let index = 0, playing = false, simT = tMin, lastWall = null;
  const slider = $("slider");
  slider.max = String(N - 1);

  function show(i) {
    index = Math.max(0, Math.min(N - 1, i));
    slider.value = String(index);
    const t = F.t[index];
    $("clock").textContent = "t = " + fmt(t, 3) + " s of " + fmt(F.t[N - 1], 3) + " s";
    drawArm(index);
    if (setWindow(t)) drawStill();
    drawPlots(index);
    const parts = [
      ["mode", D.modes[F.mode[index]] || "?"],
      ["z\u209c", fmt(F.tip_x[index], 4) + " m"],
      ["z\u2099 + H", fmt(F.tip_y[index] + D.h, 4) + " m"],
      ["f\u209c", fmt(F.f_t[index], 2) + " N"],
      ["f\u2099", fmt(F.f_n[index], 2) + " N"],
    ];
    if (D.closed_loop) parts.push(["\u03c4\u2081, \u03c4\u2082", fmt(F.u1[index], 3) + ", " + fmt(F.u2[index], 3) + " N m"]);
    const since = between(index > 0 ? F.t[index - 1] : -Infinity, t);
    const listed = since.slice(0, 4).map(evText).join("; ") + (since.length > 4 ? "; and " + (since.length - 4) + " more" : "");
    $("readout").textContent = "Frame " + (index + 1) + " of " + N + ": " + parts.map(([k, v]) => k + " " + v).join(" \u00b7 ") +
      ". Events since the previous frame: " + (since.length ? listed : "none") + ".";
    $("readout").dataset.events = String(since.length);
  }

  function pause() {
    playing = false;
    $("play").textContent = "\u25b6 play";
  }
  function tick(now) {
    if (!playing) return;
    if (lastWall !== null) simT += ((now - lastWall) / 1000) * parseFloat($("speed").value);
    lastWall = now;
    if (simT >= F.t[N - 1]) {
      show(N - 1);
      pause();
      return;
    }
    show(nearest(simT));
    requestAnimationFrame(tick);
  }
  function play() {
    if (index >= N - 1) simT = tMin;
    else simT = F.t[index];
    playing = true;
    lastWall = null;
    $("play").textContent = "\u275a\u275a pause";
    requestAnimationFrame(tick);
  }
  $("play").addEventListener("click", () => (playing ? pause() : play()));
  slider.addEventListener("input", () => {
    pause();
    show(parseInt(slider.value, 10));
  });
  const seek = (e) => {
    const r = plots.getBoundingClientRect();
    pause();
    show(nearest(wA + ((e.clientX - r.left - ML) / (G.w - ML - MR)) * (wB - wA)));
  };
  plots.addEventListener("mousedown", seek);
  plots.addEventListener("mousemove", (e) => e.buttons & 1 && seek(e));
  document.addEventListener("keydown", (e) => {
    if (e.target.tagName === "SELECT" || e.target.tagName === "INPUT") return;
    if (e.key === " ") (playing ? pause() : play());
    else if (e.key === "ArrowRight") (pause(), show(index + 1));
    else if (e.key === "ArrowLeft") (pause(), show(index - 1));
    else return;
    e.preventDefault();
  });
  window.addEventListener("resize", publishMapping);
  $("span").addEventListener("change", () => {
    setWindow(F.t[index]);
    drawStill();
    drawPlots(index);
  });

  // For scripts and tests: the frame nearest a time, and where the page drew the tip.
  window.painleve = {
    setTime(t) {
      pause();
      show(nearest(Number(t)));
      return F.t[index];
    },
    time: () => F.t[index],
    frames: N,
    events: NE,
    tipPixel() {
      const r = arm.getBoundingClientRect();
      const [x, y] = px(F.tip_x[index], F.tip_y[index]);
      return [r.left + window.scrollX + x, r.top + window.scrollY + y];
    },
  };
  // The list of events, each a link to the first frame at or after it.
  const counts = {};
  for (let j = 0; j < NE; j++) counts[evKind(j)] = (counts[evKind(j)] || 0) + 1;
  $("event-summary").textContent = NE === 0 ? "The run has no events." :
    NE + " events: " + Object.entries(counts).map(([k, n]) => n + " " + k).join(", ") +
    (E.left_out ? "; " + E.left_out + " later ones left out (the events table has them all)" : "") +
    ". Click one to show the frame after it.";
  const list = document.createDocumentFragment();
  for (let j = 0; j < NE; j++) {
    const li = document.createElement("li");
    li.dataset.kind = evKind(j);
    li.dataset.t = String(E.t[j]);
    li.style.borderLeftColor = evColor(j);
    li.textContent = evText(j);
    list.append(li);
  }
  $("event-list").append(list);
  $("event-list").addEventListener("click", (e) => {
    const li = e.target.closest("li");
    if (!li) return;
    pause();
    const te = Number(li.dataset.t);
    let i = nearest(te);
    if (F.t[i] < te && i < N - 1) i++;
    show(i);
  });

  drawStill();
  const q = new URLSearchParams(window.location.search);
  const t0 = q.has("t") ? parseFloat(q.get("t")) : NaN;
  show(ok(t0) ? nearest(t0) : 0);
})();
