// The debrief's replay of one seat in one exercise: its machine's signals (lag, position or
// speed of every axis, once a second of the seat's clock) with what happened drawn on the
// same clock (job errors red, the student's commands and parameters, hints, the instructor's
// doings), a cursor that plays the session back at a chosen speed or jumps to an entry, and
// beside it the timeline read up to the cursor with the machine's figures there.
import { useEffect, useRef, useState } from "preact/hooks";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { ApiError, http } from "../api/http";
import type { ClassInfo, Refusal, SeatReplay } from "../api/types";
import { fmt, tickLabels } from "../ui/format";
import { followWidth } from "../ui/plot";
import { RefusalLine } from "../ui/useCommand";
import { COLOURS } from "../panels/LivePlot";
import { clock } from "./SeatTile";

const HEIGHT = 220;
const SPEEDS = [1, 5, 20, 60] as const; // seat seconds per wall second
const TICK_MS = 100;
type What = "lag" | "pos" | "speed";
const WHAT_WORDS: Record<What, string> = { lag: "lag", pos: "position", speed: "speed" };

/** A mark's colour: job errors stand out, the student's doings in one colour, the rest grey. */
function markColour(kind: string, severity: string): string {
  if (kind === "job_error" || severity === "error") return "#c62828";
  if (kind === "command" || kind === "parameter") return "#1565c0";
  return "#8a94a0";
}

export function Replay(props: { c: ClassInfo; n: number; stage: number }) {
  const { c, n } = props;
  const [stage, setStage] = useState(props.stage);
  const [data, setData] = useState<SeatReplay | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [what, setWhat] = useState<What>("lag");
  const [cursor, setCursor] = useState(0);
  const [playing, setPlaying] = useState(false);
  const [speed, setSpeed] = useState<number>(SPEEDS[1]);
  const box = useRef<HTMLDivElement>(null);
  const plot = useRef<uPlot | null>(null);
  const cursorRef = useRef(0);
  cursorRef.current = cursor;

  useEffect(() => setStage(props.stage), [props.stage]);
  useEffect(() => {
    let live = true;
    setData(null);
    http.get<SeatReplay>(`/api/classes/${c.id}/seats/${n}/replay?stage=${stage}`).then(
      (r) => {
        if (!live) return;
        setData(r);
        setCursor(r.t_s.length ? r.t_s[0] : 0);
        setRefusal(null);
      },
      (e: unknown) => live && setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] }),
    );
    return () => {
      live = false;
    };
  }, [c.id, n, stage]);

  const shown = data ? data.signals.map((s, i) => [s, i] as const).filter(([s]) => s.endsWith(`.${what}`)) : [];
  const end = data?.t_s.length ? data.t_s[data.t_s.length - 1] : 0;

  useEffect(() => {
    const el = box.current;
    if (!el || !data || !data.t_s.length) return;
    const opts: uPlot.Options = {
      width: Math.max(300, el.clientWidth),
      height: HEIGHT,
      series: [
        { label: "seat time", value: (_u, v) => (v === null ? "" : clock(v)) },
        ...shown.map(([s, i], k) => ({
          label: `${s} [${data.units[i]}]`,
          stroke: COLOURS[k % COLOURS.length],
          width: 1.5,
          value: (_u: uPlot, v: number | null) => fmt(v, what === "lag" ? 4 : 2),
        })),
      ],
      scales: { x: { time: false } },
      axes: [
        { label: "seat time [s]", values: (_u, splits) => tickLabels(splits) },
        { label: WHAT_WORDS[what], values: (_u, splits) => tickLabels(splits), size: 70 },
      ],
      hooks: {
        // what happened, as thin lines over the signals; the cursor as a thick one
        draw: [
          (u) => {
            const ctx = u.ctx;
            const { top, height } = u.bbox;
            ctx.save();
            for (const m of data.marks) {
              const x = u.valToPos(m.seat_t_s, "x", true);
              ctx.strokeStyle = markColour(m.entry.kind, m.entry.severity);
              ctx.lineWidth = m.entry.kind === "job_error" ? 2 : 1;
              ctx.beginPath();
              ctx.moveTo(x, top);
              ctx.lineTo(x, top + height);
              ctx.stroke();
            }
            const x = u.valToPos(cursorRef.current, "x", true);
            ctx.strokeStyle = "#222";
            ctx.lineWidth = 3;
            ctx.beginPath();
            ctx.moveTo(x, top);
            ctx.lineTo(x, top + height);
            ctx.stroke();
            ctx.restore();
          },
        ],
      },
    };
    const series = shown.map(([, i]) => data.values[i]);
    const u = new uPlot(opts, [data.t_s, ...series] as uPlot.AlignedData, el);
    plot.current = u;
    const stop = followWidth(u, el, HEIGHT);
    return () => {
      plot.current = null;
      stop();
    };
  }, [data, what]);

  useEffect(() => plot.current?.redraw(false, false), [cursor]);

  useEffect(() => {
    if (!playing) return;
    const timer = setInterval(() => {
      const next = cursorRef.current + (speed * TICK_MS) / 1000;
      if (next >= end) {
        setCursor(end);
        setPlaying(false);
      } else setCursor(next);
    }, TICK_MS);
    return () => clearInterval(timer);
  }, [playing, speed, end]);

  const stages = Array.from({ length: props.stage + 1 }, (_, k) => k);
  // the sample at (or just before) the cursor: the figures the machine showed then
  const at = data ? Math.max(0, data.t_s.findIndex((t) => t > cursor) - 1) : 0;
  const idx = data && data.t_s.length && cursor >= end ? data.t_s.length - 1 : at;
  const past = data ? data.marks.filter((m) => m.seat_t_s <= cursor + 1e-6) : [];
  return (
    <section class="replay" data-testid="replay">
      <h3>Replay</h3>
      <div class="replay-bar">
        {c.exercises.length > 1 ? (
          <label>
            Exercise{" "}
            <select value={stage} data-testid="replay-stage" onChange={(e) => setStage(Number((e.target as HTMLSelectElement).value))}>
              {stages.map((k) => (
                <option key={k} value={k}>{k + 1}. {c.exercises[k]}</option>
              ))}
            </select>
          </label>
        ) : null}
        <label>
          Show{" "}
          <select value={what} data-testid="replay-what" onChange={(e) => setWhat((e.target as HTMLSelectElement).value as What)}>
            {(Object.keys(WHAT_WORDS) as What[]).map((w) => (
              <option key={w} value={w}>{WHAT_WORDS[w]}</option>
            ))}
          </select>
        </label>
        <button type="button" class="secondary" data-testid="replay-play" disabled={!data?.t_s.length}
          onClick={() => {
            if (!playing && cursor >= end && data?.t_s.length) setCursor(data.t_s[0]);
            setPlaying(!playing);
          }}>
          {playing ? "❚❚ Pause" : "▶ Play"}
        </button>
        <select value={speed} aria-label="replay speed" data-testid="replay-speed" onChange={(e) => setSpeed(Number((e.target as HTMLSelectElement).value))}>
          {SPEEDS.map((s) => (
            <option key={s} value={s}>{s}×</option>
          ))}
        </select>
        <input type="range" min={data?.t_s[0] ?? 0} max={end} step={0.1} value={cursor} aria-label="seat time" data-testid="replay-cursor"
          onInput={(e) => { setPlaying(false); setCursor(Number((e.target as HTMLInputElement).value)); }} />
        <span class="num" data-testid="replay-time">{clock(cursor)} of {clock(end)}</span>
      </div>
      <RefusalLine refusal={refusal} />
      {data && !data.t_s.length ? (
        <p class="hint" data-testid="replay-empty">Nothing recorded in this exercise yet: the seat's clock has not run.</p>
      ) : null}
      <div class="replay-cols">
        <div>
          <div ref={box} class="replay-chart" data-testid="replay-chart" />
          {data && data.t_s.length ? (
            <p class="mono replay-now" data-testid="replay-now">
              {shown.map(([s, i]) => `${s} ${fmt(data.values[i][idx] ?? null, what === "lag" ? 4 : 2)} ${data.units[i]}`).join(" · ")}
            </p>
          ) : null}
        </div>
        <ol class="replay-marks" data-testid="replay-marks">
          {data?.marks.map((m) => (
            <li key={m.entry.id} class={m.seat_t_s <= cursor + 1e-6 ? "past" : "future"} data-kind={m.entry.kind}>
              <button type="button" class="link num" onClick={() => { setPlaying(false); setCursor(m.seat_t_s); }} title="go there">
                {clock(m.seat_t_s)}
              </button>{" "}
              <span style={{ color: markColour(m.entry.kind, m.entry.severity) }}>{m.entry.code ? `${m.entry.code} ` : ""}{m.entry.text}</span>
              {m.entry.actor ? <span class="hint"> · {m.entry.actor}</span> : null}
            </li>
          ))}
          {data && !data.marks.length ? <li class="hint">nothing in its history</li> : null}
        </ol>
      </div>
      {data ? <p class="hint" data-testid="replay-count">{past.length} of {data.marks.length} entries up to the cursor</p> : null}
    </section>
  );
}
