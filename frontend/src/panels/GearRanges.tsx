// The main spindle's six gear ranges (000 §2.8.2; spindel[i].range_table[j].min_speed /
// max_speed, P-CHAN-00058/00055) as bars on one rpm scale: drag a bar's ends or type the
// limits, overlaps are highlighted, and the stage the NC's automatic selection picks for each
// typed S is previewed by the service with the kernel's own rule (nc_sim/spindle/gears.py).
// Gear g is M(39+g), range_table[g-1] and the axis's gear record getriebe[g-1].
import type { JSX } from "preact";
import { useEffect, useRef, useState } from "preact/hooks";
import type { GearSelectionResult, Refusal } from "../api/types";
import { previewGears } from "../state/calculators";
import { paramsVersion } from "../state/params";
import { machineId, status } from "../state/session";
import { RefusalLine } from "../ui/useCommand";
import { gearName } from "../ui/format";
import { ApplyBar, checkNumber, refusalOf } from "./CalcParts";

const GEARS = [1, 2, 3, 4, 5, 6];
const U16 = 65535;
const W = 760;
const LEFT = 150; // the labels' column
const ROW = 26;
const TOP = 8;
const SNAP_RPM = 10; // dragging moves the limits in steps of this

type Row = [string, string]; // min, max as typed (rpm)

/** Ranges that share speeds: [gear a, gear b, from, to]. */
export function overlaps(ranges: { min: number; max: number }[]): [number, number, number, number][] {
  const out: [number, number, number, number][] = [];
  ranges.forEach((a, i) =>
    ranges.forEach((b, j) => {
      if (j <= i || a.max <= 0 || b.max <= 0) return;
      const lo = Math.max(a.min, b.min);
      const hi = Math.min(a.max, b.max);
      if (lo <= hi) out.push([i + 1, j + 1, lo, hi]);
    }),
  );
  return out;
}

const LOG_FLOOR_RPM = 10; // the logarithmic scale starts here (0 is drawn at its left edge)

/** The rpm scale up to `top`: position (0..1) of a speed, the speed at a position, ticks.
 * Logarithmic by default: the manual's table spans 50 to 7000 rpm, a linear scale squeezes
 * the low ranges into a few pixels. */
function scale(bottom: number, top: number, log: boolean): { at: (rpm: number) => number; rpm: (u: number) => number; ticks: number[] } {
  if (log) {
    const lo = Math.floor(Math.log10(Math.max(LOG_FLOOR_RPM, bottom / 1.2)) * 4) / 4; // just below the lowest limit
    const hi = Math.ceil(Math.log10(Math.max(100, top) * 1.04) * 4) / 4;
    const ticks = [];
    for (let e = Math.floor(lo); e <= hi + 1e-9; e++)
      for (const m of [1, 2, 5]) if (Math.abs(Math.log10(m * 10 ** e) - (lo + hi) / 2) <= (hi - lo) / 2 + 1e-9) ticks.push(m * 10 ** e);
    return {
      at: (rpm) => (Math.log10(Math.max(LOG_FLOOR_RPM, rpm)) - lo) / (hi - lo),
      rpm: (u) => 10 ** (lo + u * (hi - lo)),
      ticks,
    };
  }
  const raw = Math.max(100, top) / 8;
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((v) => v >= raw) ?? 10 * mag;
  const end = Math.ceil((Math.max(100, top) * 1.04) / step) * step;
  const ticks = [];
  for (let v = 0; v <= end + 1e-9; v += step) ticks.push(v);
  return { at: (rpm) => Math.min(rpm, end) / end, rpm: (u) => u * end, ticks };
}

export function GearRanges() {
  const sp = status.value?.axes.find((a) => a.kind === "spindle" && a.gear != null);
  const [rows, setRows] = useState<Row[] | null>(null);
  const [speeds, setSpeeds] = useState("950");
  const [current, setCurrent] = useState<number | null>(null);
  const [way, setWay] = useState<"" | "0" | "1">("");
  const [preview, setPreview] = useState<GearSelectionResult | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [drag, setDrag] = useState<{ row: number; end: 0 | 1 } | null>(null);
  const [log, setLog] = useState(true);
  const svg = useRef<SVGSVGElement>(null);

  // the machine's table (and its search direction) to start from, again after a write
  useEffect(() => {
    previewGears({ speeds_rpm: [] }).then(
      (r) => {
        setRows(r.ranges.map((g) => [String(g.min_rpm), String(g.max_rpm)]));
        setWay(String(r.range_way ? 1 : 0) as "0" | "1");
        setRefusal(null);
      },
      (e) => setRefusal(refusalOf(e)),
    );
  }, [machineId.value, paramsVersion.value]);
  useEffect(() => setCurrent(null), [machineId.value]);

  const checks = (rows ?? []).map(([lo, hi], i) => {
    const min = checkNumber(lo, `M${40 + i} min`, 0, U16, "rpm", false, true);
    const max = checkNumber(hi, `M${40 + i} max`, 0, U16, "rpm", false, true);
    const order = typeof min === "number" && typeof max === "number" && max > 0 && min > max ? `M${40 + i}: min above max` : null;
    return { min, max, order };
  });
  const sList = speeds.split(/[\s,;]+/).filter(Boolean).map((t) => t.replace(/^S/i, ""));
  const sChecks = sList.map((t) => checkNumber(t, `S${t}`, 0, 1e5, "rpm"));
  const errors = [...checks.flatMap((c) => [c.min, c.max, c.order]), ...sChecks].filter((v): v is string => typeof v === "string");
  const ranges = checks.map((c) => ({ min: typeof c.min === "number" ? c.min : 0, max: typeof c.max === "number" ? c.max : 0 }));
  const gearNow = current ?? sp?.gear ?? 1;
  const key = JSON.stringify([ranges, sList, gearNow, way]);

  useEffect(() => {
    if (!rows || errors.length) return;
    const id = setTimeout(() => {
      previewGears({
        ranges: ranges.map((r) => ({ min_rpm: r.min, max_rpm: r.max })),
        speeds_rpm: sChecks as number[],
        current_gear: gearNow,
        range_way: way === "" ? null : (Number(way) as 0 | 1),
      }).then(
        (r) => {
          setPreview(r);
          setRefusal(null);
        },
        (e) => setRefusal(refusalOf(e)),
      );
    }, 120);
    return () => clearTimeout(id);
  }, [key, errors.length === 0]);

  if (!rows) return <RefusalLine refusal={refusal} id="gear-refusal" />;
  const typedS = sChecks.filter((v): v is number => typeof v === "number" && v > 0);
  const sc = scale(Math.min(...ranges.filter((r) => r.max > 0).map((r) => Math.max(r.min, 1)), ...typedS), Math.max(...ranges.map((r) => r.max), ...(sChecks.filter((v) => typeof v === "number") as number[])), log);
  const x = (rpm: number) => LEFT + sc.at(rpm) * (W - LEFT - 24);
  const H = TOP + GEARS.length * ROW + 26;
  const shared = overlaps(ranges);
  const last = preview?.steps.at(-1);
  const chosen = last?.gear ?? null;
  const setRow = (i: number, j: 0 | 1, v: string) => setRows(rows.map((r, k) => (k === i ? ((j ? [r[0], v] : [v, r[1]]) as Row) : r)));

  function onMove(e: JSX.TargetedPointerEvent<SVGSVGElement>) {
    if (!drag || !svg.current) return;
    const box = svg.current.getBoundingClientRect();
    const vx = ((e.clientX - box.left) / box.width) * W;
    const u = Math.max(0, Math.min(1, (vx - LEFT) / (W - LEFT - 24)));
    const rpm = Math.round(sc.rpm(u) / SNAP_RPM) * SNAP_RPM;
    setRow(drag.row, drag.end, String(Math.max(0, Math.min(U16, rpm))));
  }

  const ticks = sc.ticks;
  return (
    <div class="gear-editor" data-testid="calc-gear-ranges">
      <p class="assist-what">
        Six speed ranges of the main spindle {preview?.spindle ?? sp?.name ?? ""} (spindel[{preview?.spindle_index ?? 0}].range_table[0–5], rpm); overlaps
        are allowed, unused ranges are 0/0. {preview && !preview.gear_change ? "Gear change is off (main_spindle_gear_change, P-CHAN-00052): S runs in the current stage. " : ""}
        With automatic selection (autom_range{preview ? ` = ${preview.automatic ? 1 : 0}` : ""}) the NC keeps the current stage when its range holds S,
        otherwise it searches the table {way === "1" ? "top-down (6 → 1)" : "bottom-up (1 → 6)"} (range_way) for the first range that holds S (000 §2.8.2).
      </p>
      <div class="row">
        <button type="button" class="secondary" data-testid="gear-scale-kind" onClick={() => setLog(!log)}>
          {log ? "linear scale" : "logarithmic scale"}
        </button>
        <span class="hint">Drag a bar's ends (steps of {SNAP_RPM} rpm) or type the limits below.</span>
      </div>
      <svg ref={svg} class={`gear-scale${drag ? " dragging" : ""}`} viewBox={`0 0 ${W} ${H}`} role="img" aria-label="gear ranges on an rpm scale"
        data-testid="gear-scale" onPointerMove={onMove} onPointerUp={() => setDrag(null)} onPointerLeave={() => setDrag(null)}>
        {ticks.map((t) => (
          <g key={t}>
            <line x1={x(t)} x2={x(t)} y1={TOP} y2={H - 20} class="tick" />
            <text x={x(t)} y={H - 6} class="tick-label" text-anchor="middle">
              {t}
            </text>
          </g>
        ))}
        <text x={4} y={H - 6} class="tick-label">
          rpm ({log ? "logarithmic" : "linear"})
        </text>
        {GEARS.map((g, i) => {
          const r = ranges[i];
          const y = TOP + i * ROW;
          const used = r.max > 0;
          const cls = ["bar", g === chosen ? "chosen" : "", g === gearNow ? "current" : "", shared.some((o) => o[0] === g || o[1] === g) ? "shared" : ""].join(" ");
          return (
            <g key={g} data-testid={`gear-row-${g}`} data-chosen={g === chosen ? "1" : "0"}>
              <text x={4} y={y + 17} class={g === chosen ? "row-label chosen" : "row-label"}>
                {gearName(g)}
              </text>
              {used ? (
                <>
                  <rect x={x(r.min)} y={y + 5} width={Math.max(2, x(r.max) - x(r.min))} height={ROW - 10} class={cls}>
                    <title>{`M${39 + g}: ${r.min}–${r.max} rpm`}</title>
                  </rect>
                  {([0, 1] as const).map((endIdx) => (
                    <rect key={endIdx} x={x(endIdx ? r.max : r.min) - 4} y={y + 3} width={8} height={ROW - 6} class="handle"
                      data-testid={`gear-handle-${g}-${endIdx ? "max" : "min"}`}
                      onPointerDown={(e) => {
                        svg.current?.setPointerCapture(e.pointerId);
                        setDrag({ row: i, end: endIdx });
                      }}>
                      <title>{`drag: M${39 + g} ${endIdx ? "max" : "min"}_speed`}</title>
                    </rect>
                  ))}
                </>
              ) : (
                <text x={LEFT + 4} y={y + 17} class="tick-label">
                  unused (0/0)
                </text>
              )}
            </g>
          );
        })}
        {shared.map(([a, b, lo, hi]) => (
          <rect key={`${a}-${b}`} x={x(lo)} y={TOP + (a - 1) * ROW + 2} width={Math.max(2, x(hi) - x(lo))} height={(b - a + 1) * ROW - 4} class="overlap"
            data-testid={`gear-overlap-${a}-${b}`}>
            <title>{`M${39 + a} and M${39 + b} overlap ${lo}–${hi} rpm`}</title>
          </rect>
        ))}
        {(sChecks.filter((v) => typeof v === "number") as number[]).map((s, k) => (
          <g key={`${s}-${k}`} class="s-mark">
            <line x1={x(s)} x2={x(s)} y1={TOP} y2={H - 20} />
            <text x={x(s) + 3} y={TOP + 8 + (k % 4) * 10} class="s-label">
              S{s}
            </text>
          </g>
        ))}
      </svg>
      <div class="gear-grid">
        <table class="meas-table" data-testid="gear-table">
          <thead>
            <tr>
              <th>M</th>
              <th>gear</th>
              <th>record</th>
              <th>min_speed [rpm]</th>
              <th>max_speed [rpm]</th>
              <th>overlaps</th>
            </tr>
          </thead>
          <tbody>
            {GEARS.map((g, i) => (
              <tr key={g} class={g === chosen ? "chosen" : ""}>
                <td class="mono">M{39 + g}</td>
                <td>{g}</td>
                <td class="mono">getriebe[{g - 1}]</td>
                {([0, 1] as const).map((j) => {
                  const c = j ? checks[i].max : checks[i].min;
                  const bad = typeof c === "string" || (j === 1 && !!checks[i].order);
                  return (
                    <td key={j}>
                      <input size={6} data-testid={`gear-${j ? "max" : "min"}-${g}`} value={rows[i][j]} aria-invalid={bad}
                        title={typeof c === "string" ? c : (j === 1 && checks[i].order) || ""} onInput={(e) => setRow(i, j, (e.target as HTMLInputElement).value)} />
                    </td>
                  );
                })}
                <td class="hint" data-testid={`gear-overlaps-${g}`}>
                  {shared
                    .filter((o) => o[0] === g || o[1] === g)
                    .map((o) => `M${39 + (o[0] === g ? o[1] : o[0])} ${o[2]}–${o[3]}`)
                    .join(", ")}
                </td>
              </tr>
            ))}
          </tbody>
        </table>
        <div class="gear-preview">
          <label class="assist-field">
            <span>Programmed S (one or more, in order)</span>
            <span class="row">
              <input data-testid="gear-s" size={18} value={speeds} onInput={(e) => setSpeeds((e.target as HTMLInputElement).value)} />
              <span>rpm</span>
            </span>
          </label>
          <div class="row">
            <label class="assist-field">
              <span>Stage before the first S</span>
              <select data-testid="gear-current" value={String(gearNow)} onChange={(e) => setCurrent(Number((e.target as HTMLSelectElement).value))}>
                {GEARS.map((g) => (
                  <option key={g} value={g}>
                    M{39 + g}
                    {g === sp?.gear ? " (now)" : ""}
                  </option>
                ))}
              </select>
            </label>
            <label class="assist-field">
              <span>Search (range_way)</span>
              <select data-testid="gear-way" value={way} onChange={(e) => setWay((e.target as HTMLSelectElement).value as "0" | "1")}>
                <option value="0">0 bottom-up</option>
                <option value="1">1 top-down</option>
              </select>
            </label>
          </div>
          {errors.map((e) => (
            <span key={e} class="inline-error" role="alert">
              {e}
            </span>
          ))}
          {preview ? (
            <ol class="gear-steps" data-testid="gear-steps">
              {preview.steps.map((s, k) => (
                <li key={k} data-testid={`gear-step-${k}`} data-m={s.m ?? ""} class={s.error ? "bad" : ""}>
                  S{s.speed_rpm} →{" "}
                  {s.gear ? (
                    <>
                      <b>M{s.m}</b> (gear {s.gear}, getriebe[{s.gear - 1}]) {s.change ? "change: M" + s.m + " to the PLC" : "no change"}
                    </>
                  ) : (
                    <>
                      <b>refused</b> {s.error}: {s.detail}
                    </>
                  )}
                </li>
              ))}
            </ol>
          ) : null}
          <RefusalLine refusal={refusal} id="gear-refusal" />
          {preview && preview.changes.length ? (
            <table class="meas-table assist-changes" data-testid="gear-changes">
              <caption>Edited ranges (channel list)</caption>
              <tbody>
                {preview.changes.map((c) => (
                  <tr key={c.parameter}>
                    <td class="mono">{c.parameter}</td>
                    <td class="num">{String(c.before)}</td>
                    <td>→</td>
                    <td class="num">
                      <b>{String(c.after)}</b>
                    </td>
                  </tr>
                ))}
              </tbody>
            </table>
          ) : null}
          <ApplyBar assistant="gear-ranges" changes={errors.length ? [] : (preview?.changes ?? [])} testid="gear" />
        </div>
      </div>
    </div>
  );
}
