// The tool path in the program's plane, to scale (1 mm across = 1 mm up): the commanded path
// from the preview (rapids dashed), and the actual path of the two axes drawn live from
// telemetry (a bounded buffer, cleared when a new run of the program starts). Wheel zooms
// about the pointer, drag pans, Fit resets.
import { useEffect, useRef, useState } from "preact/hooks";
import type { ChannelStatus, ProgramPreview } from "../api/types";
import type { Rings } from "../state/rings";
import { status } from "../state/session";
import { frameListeners, unwant, want } from "../state/telemetry";
import { type DrawLoop, drawLoop } from "../ui/drawLoop";
import { fmt } from "../ui/format";

const MAX_DRAWS_PER_S = 25; // the actual path grows smoothly to the eye
const MAX_ACTUAL = 20_000; // points of the actual path kept (the oldest go first)
const MIN_STEP_MM = 0.001; // a new actual point only once the tool moved this far
const MARGIN_PX = 40;
// a run continues from these states (cycle start after feedhold or a single-block stop);
// from any other it starts anew
const IN_A_RUN = new Set<ChannelStatus["state"]>(["running", "held", "block_end"]);
const COLOURS = { rapid: "#7a8794", feed: "#0b63b6", current: "#f2a900", actual: "rgba(214, 39, 40, 0.75)", grid: "#e4e9ef" };

interface View {
  cx: number; // mm at the centre
  cy: number;
  pxPerMm: number;
}

/** A round grid step (1, 2 or 5 × 10^n mm) of about `px` pixels. */
function gridStep(pxPerMm: number, px = 80): number {
  const raw = px / pxPerMm;
  const p = 10 ** Math.floor(Math.log10(raw));
  return [1, 2, 5, 10].map((k) => k * p).find((s) => s >= raw) ?? 10 * p;
}

function bounds(preview: ProgramPreview | null): [number, number, number, number] | null {
  let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
  for (const s of preview?.segments ?? [])
    for (const [x, y] of s.points) {
      x0 = Math.min(x0, x); x1 = Math.max(x1, x);
      y0 = Math.min(y0, y); y1 = Math.max(y1, y);
    }
  return Number.isFinite(x0) ? [x0, y0, x1, y1] : null;
}

function fit(preview: ProgramPreview | null, w: number, h: number): View {
  const b = bounds(preview) ?? [-50, -50, 50, 50];
  const spanX = Math.max(b[2] - b[0], 1), spanY = Math.max(b[3] - b[1], 1);
  const pxPerMm = Math.min((w - 2 * MARGIN_PX) / spanX, (h - 2 * MARGIN_PX) / spanY);
  return { cx: (b[0] + b[2]) / 2, cy: (b[1] + b[3]) / 2, pxPerMm: Math.max(pxPerMm, 1e-6) };
}

export function ToolpathPlot(props: { preview: ProgramPreview | null; blockLine: number | null }) {
  const canvas = useRef<HTMLCanvasElement>(null);
  const view = useRef<View | null>(null);
  const fitted = useRef(true); // follows the program's extent until the user zooms or pans
  const actual = useRef<number[]>([]); // h0, v0, h1, v1, ...
  const dirty = useRef(true);
  const loopRef = useRef<DrawLoop | null>(null);
  /** Something changed the picture: draw it again (in the next frame at most). */
  const markDirty = () => {
    dirty.current = true;
    loopRef.current?.kick();
  };
  const [cursor, setCursor] = useState<[number, number] | null>(null);
  const [, redraw] = useState(0);
  const axes = props.preview?.axes ?? null;
  const [h, v] = axes ?? ["", ""];

  // the actual positions of the plane's two axes, as frames arrive
  useEffect(() => {
    if (!h || !v) return;
    const owner = "toolpath";
    const names = [`${h}.pos_act_mm`, `${v}.pos_act_mm`];
    want(owner, names);
    let lastT = -Infinity;
    const take = (r: Rings) => {
      const [t, hs, vs] = r.window(1, names);
      const a = actual.current;
      for (let i = 0; i < t.length; i++) {
        if (t[i] <= lastT || Number.isNaN(hs[i]) || Number.isNaN(vs[i])) continue;
        lastT = t[i];
        const n = a.length;
        if (n && Math.hypot(hs[i] - a[n - 2], vs[i] - a[n - 1]) < MIN_STEP_MM) continue;
        a.push(hs[i], vs[i]);
        dirty.current = true;
      }
      if (dirty.current) loopRef.current?.kick();
      if (a.length > 2 * MAX_ACTUAL) a.splice(0, a.length - 2 * MAX_ACTUAL);
    };
    frameListeners.add(take);
    return () => {
      frameListeners.delete(take);
      unwant(owner);
      actual.current = [];
    };
  }, [h, v]);

  // a new run draws its own actual path: the trace of the runs before it is dropped (the
  // status may skip "running" for a short block, so any entry into a run counts)
  const runState = status.value?.channel.state;
  const lastState = useRef(runState);
  useEffect(() => {
    const before = lastState.current;
    lastState.current = runState;
    if (runState && before && IN_A_RUN.has(runState) && !IN_A_RUN.has(before)) {
      const a = actual.current;
      actual.current = a.length ? a.slice(-2) : []; // from where the tool stands
      markDirty();
    }
  }, [runState]);

  useEffect(markDirty, [props.preview, props.blockLine]);

  useEffect(() => {
    const el = canvas.current;
    if (!el) return;
    const loop = drawLoop(
      () => {
        const w = el.clientWidth, ht = el.clientHeight;
        const dpr = window.devicePixelRatio || 1;
        if (el.width !== Math.round(w * dpr) || el.height !== Math.round(ht * dpr)) {
          el.width = Math.round(w * dpr);
          el.height = Math.round(ht * dpr);
        }
        if (fitted.current) view.current = fit(props.preview, w, ht);
        if (!view.current) return;
        dirty.current = false;
        const ctx = el.getContext("2d");
        if (!ctx) return;
        paint(ctx, dpr, w, ht, view.current, props.preview, props.blockLine, actual.current);
        const a = actual.current; // for tests and tools: how much of the actual path is drawn, from where
        el.dataset.actualPoints = String(a.length / 2);
        el.dataset.actualFrom = a.length ? `${a[0].toFixed(3)} ${a[1].toFixed(3)}` : "";
      },
      MAX_DRAWS_PER_S,
    );
    loopRef.current = loop;
    const resized = new ResizeObserver(markDirty);
    resized.observe(el);
    markDirty();
    return () => {
      loop.stop();
      loopRef.current = null;
      resized.disconnect();
    };
  }, [props.preview, props.blockLine]);

  const toMm = (e: MouseEvent): [number, number] | null => {
    const el = canvas.current, vw = view.current;
    if (!el || !vw) return null;
    const r = el.getBoundingClientRect();
    return [vw.cx + (e.clientX - r.left - r.width / 2) / vw.pxPerMm, vw.cy - (e.clientY - r.top - r.height / 2) / vw.pxPerMm];
  };
  const drag = useRef<{ x: number; y: number } | null>(null);
  const segments = props.preview?.segments.length ?? 0;
  return (
    <div class="toolpath" data-testid="toolpath" data-segments={segments}>
      <div class="row">
        <span class="hint">
          {props.preview ? `${props.preview.plane}: ${h} across, ${v} up (mm)` : "no preview"}
          {props.preview?.truncated ? " — too long to draw whole: the rest is left out" : ""}
        </span>
        <span class="legend"><i class="sw rapid" /> rapid <i class="sw feed" /> feed <i class="sw actual" /> actual</span>
        <span class="hint mono" data-testid="toolpath-cursor">{cursor ? `${h} ${fmt(cursor[0], 3)}  ${v} ${fmt(cursor[1], 3)}` : ""}</span>
        <button type="button" class="secondary" data-testid="toolpath-fit"
          onClick={() => { fitted.current = true; markDirty(); redraw((n) => n + 1); }}>
          Fit
        </button>
        <button type="button" class="secondary" data-testid="toolpath-clear" title="forget the actual path drawn so far"
          onClick={() => { actual.current = []; markDirty(); }}>
          Clear actual
        </button>
      </div>
      <canvas
        ref={canvas}
        data-testid="toolpath-canvas"
        aria-label="tool path plot"
        onWheel={(e) => {
          e.preventDefault();
          const vw = view.current, at = toMm(e);
          if (!vw || !at) return;
          const k = Math.exp(-e.deltaY * 0.0015);
          // zoom about the pointer: the point under it stays put
          view.current = { cx: at[0] - (at[0] - vw.cx) / k, cy: at[1] - (at[1] - vw.cy) / k, pxPerMm: vw.pxPerMm * k };
          fitted.current = false;
          markDirty();
        }}
        onMouseDown={(e) => (drag.current = { x: e.clientX, y: e.clientY })}
        onMouseMove={(e) => {
          setCursor(toMm(e));
          const d = drag.current, vw = view.current;
          if (!d || !vw || !(e.buttons & 1)) return;
          view.current = { ...vw, cx: vw.cx - (e.clientX - d.x) / vw.pxPerMm, cy: vw.cy + (e.clientY - d.y) / vw.pxPerMm };
          drag.current = { x: e.clientX, y: e.clientY };
          fitted.current = false;
          markDirty();
        }}
        onMouseUp={() => (drag.current = null)}
        onMouseLeave={() => { drag.current = null; setCursor(null); }}
        onDblClick={() => { fitted.current = true; markDirty(); }}
      />
    </div>
  );
}

function paint(
  ctx: CanvasRenderingContext2D, dpr: number, w: number, h: number, vw: View,
  preview: ProgramPreview | null, blockLine: number | null, actual: number[],
) {
  const X = (mm: number) => w / 2 + (mm - vw.cx) * vw.pxPerMm;
  const Y = (mm: number) => h / 2 - (mm - vw.cy) * vw.pxPerMm;
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, w, h);
  // grid with labels in mm
  const step = gridStep(vw.pxPerMm);
  ctx.strokeStyle = COLOURS.grid;
  ctx.fillStyle = "#5d6b7a";
  ctx.font = "11px DejaVu Sans, sans-serif";
  ctx.lineWidth = 1;
  ctx.setLineDash([]);
  const left = vw.cx - w / 2 / vw.pxPerMm, right = vw.cx + w / 2 / vw.pxPerMm;
  const bottom = vw.cy - h / 2 / vw.pxPerMm, top = vw.cy + h / 2 / vw.pxPerMm;
  const digits = Math.max(0, -Math.floor(Math.log10(step)));
  ctx.beginPath();
  for (let x = Math.ceil(left / step) * step; x <= right; x += step) {
    ctx.moveTo(Math.round(X(x)) + 0.5, 0);
    ctx.lineTo(Math.round(X(x)) + 0.5, h);
    ctx.fillText(x.toFixed(digits), X(x) + 3, h - 4);
  }
  for (let y = Math.ceil(bottom / step) * step; y <= top; y += step) {
    ctx.moveTo(0, Math.round(Y(y)) + 0.5);
    ctx.lineTo(w, Math.round(Y(y)) + 0.5);
    ctx.fillText(y.toFixed(digits), 3, Y(y) - 3);
  }
  ctx.stroke();
  for (const s of preview?.segments ?? []) {
    const current = blockLine !== null && s.line === blockLine;
    ctx.strokeStyle = current ? COLOURS.current : s.rapid ? COLOURS.rapid : COLOURS.feed;
    ctx.lineWidth = current ? 3 : 1.5;
    ctx.setLineDash(s.rapid ? [6, 4] : []);
    ctx.beginPath();
    s.points.forEach(([x, y], i) => (i ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
    ctx.stroke();
  }
  if (actual.length >= 4) {
    ctx.strokeStyle = COLOURS.actual;
    ctx.lineWidth = 1.25;
    ctx.setLineDash([]);
    ctx.beginPath();
    ctx.moveTo(X(actual[0]), Y(actual[1]));
    for (let i = 2; i < actual.length; i += 2) ctx.lineTo(X(actual[i]), Y(actual[i + 1]));
    ctx.stroke();
  }
  if (actual.length >= 2) {
    // where the tool is now
    const n = actual.length;
    ctx.fillStyle = COLOURS.actual;
    ctx.beginPath();
    ctx.arc(X(actual[n - 2]), Y(actual[n - 1]), 4, 0, 2 * Math.PI);
    ctx.fill();
  }
}
