// Measurements of one channel over the window between the cursors (or the visible range),
// computed by the service: max |value| (max lag), overshoot, rise time, settling, steady mean;
// with an overlaid trace, its figures for the same channel and window side by side.
import { Fragment } from "preact";
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { Measurements as M, TraceDetail } from "../api/types";
import { measure } from "../state/scope";
import { fmt } from "../ui/format";
import type { Cursors } from "./CaptureChart";

/** The service's figures for `channel` of trace `id` over the window, refetched as they change
 * (debounced while cursors move); null while none or when `id` is "". */
function useMeasure(id: string, channel: string, band: number, win: [number, number] | null) {
  const [m, setM] = useState<M | null>(null);
  const [error, setError] = useState("");
  useEffect(() => {
    if (!id) return setM(null);
    const q = new URLSearchParams({ channel, band_pct: String(band) });
    if (win) {
      q.set("t0_s", String(win[0]));
      q.set("t1_s", String(win[1]));
    }
    const timer = setTimeout(() => {
      http
        .get<M>(`/api/traces/${id}/measure?${q}`)
        .then((r) => {
          setM(r);
          setError("");
        })
        .catch((e) => {
          setM(null);
          setError(e instanceof ApiError ? e.refusal.message : String(e));
        });
    }, 120);
    return () => clearTimeout(timer);
  }, [id, channel, band, win?.[0], win?.[1]]);
  return { m, error };
}

type Row = [label: string, id: string, value: (m: M) => string, title?: string];

export function Measurements(props: {
  detail: TraceDetail;
  cursors: Cursors;
  range: [number, number] | null;
  /** an overlaid trace: measured alike, in a second column */
  compare?: TraceDetail | null;
}) {
  const { detail, cursors, range } = props;
  // the channel and band stay for the session (state/scope.ts), across tabs
  const { channel, band } = measure.value;
  const setChannel = (c: string) => measure.patch({ channel: c });
  const setBand = (b: number) => measure.patch({ band: b });
  const names = detail.channels.map((c) => c.name);
  const ch = names.includes(channel) ? channel : (detail.channels.find((c) => c.kind === "float")?.name ?? names[0]);
  const [a, b] = cursors;
  const win: [number, number] | null = a !== null && b !== null ? [Math.min(a, b), Math.max(a, b)] : range;
  const source = a !== null && b !== null ? "between the cursors" : "visible range";

  const { m, error } = useMeasure(detail.id, ch, band, win);
  const other = props.compare && props.compare.channels.some((c) => c.name === ch) ? props.compare : null;
  const { m: mo } = useMeasure(other?.id ?? "", ch, band, win);
  const rows: Row[] = [
    ["window", "window", (r) => `${fmt(r.t0_s, 3)} … ${fmt(r.t1_s, 3)} s (${r.samples} samples)`],
    ["max |value|", "max-abs", (r) => `${fmt(r.max_abs, 4)} ${r.unit} at ${fmt(r.t_max_abs_s, 3)} s`, "e.g. the maximum lag"],
    ["overshoot", "overshoot", (r) => (r.overshoot_pct === null ? "—" : `${fmt(r.overshoot_pct, 2)} %`), "beyond the final value, in % of the step"],
    // a step down falls: the same 10 %/90 % of the step, named as it goes
    [m && m.final < m.initial ? "fall time 90–10 %" : "rise time 10–90 %", "rise", (r) => (r.rise_time_s === null ? "—" : `${fmt(r.rise_time_s * 1000, 1)} ms`)],
    ["noise σ", "noise", (r) => `${fmt(r.noise, 6)} ${r.unit}`, "from neighbouring samples; a step must exceed 10 σ"],
    [`settling (±${fmt(m?.band, 4)} ${m?.unit ?? ""})`, "settling", (r) => (r.settling_time_s === null ? "not settled" : `${fmt(r.settling_time_s * 1000, 1)} ms`), "from the trigger until it stays in the band"],
    ["steady mean", "final", (r) => `${fmt(r.final, 4)} ${r.unit}`, "mean of the last 10 % of the window"],
    ["min / max", "minmax", (r) => `${fmt(r.minimum, 4)} / ${fmt(r.maximum, 4)} ${r.unit}`],
  ];
  const noStep = (
    <tr>
      <td colSpan={other ? 3 : 2} class="hint" data-testid="meas-no-step">
        no step stands out of the noise here (or it comes back): no overshoot or rise time
      </td>
    </tr>
  );
  return (
    <div class="measurements" data-testid="measurements">
      <div class="plot-tools">
        <label>
          Measure{" "}
          <select value={ch} data-testid="meas-channel" onChange={(e) => setChannel((e.target as HTMLSelectElement).value)}>
            {names.map((n) => (
              <option key={n} value={n}>{n}</option>
            ))}
          </select>
        </label>
        <label>
          band ±<input type="number" min={0.1} max={100} step={0.5} value={band} class="narrow"
            onInput={(e) => setBand(Number((e.target as HTMLInputElement).value))} /> %
        </label>
        <span class="hint">{source}</span>
      </div>
      {error ? <p class="refusal">{error}</p> : null}
      {m ? (
        <table class="meas-table">
          {other ? (
            <thead>
              <tr>
                <th />
                <th data-testid="meas-head-shown">{detail.name || detail.trigger || "shown"}</th>
                <th data-testid="meas-head-overlay">{other.name || other.trigger || "overlay"} (dashed)</th>
              </tr>
            </thead>
          ) : null}
          <tbody>
            {rows.map(([label, id, value, title]) => (
              <Fragment key={id}>
                <tr title={title}>
                  <th>{label}</th>
                  <td data-testid={`meas-${id}`}>{value(m)}</td>
                  {other ? <td data-testid={`meas-overlay-${id}`}>{mo ? value(mo) : "—"}</td> : null}
                </tr>
                {id === "max-abs" && !m.step_found ? noStep : null}
              </Fragment>
            ))}
          </tbody>
        </table>
      ) : null}
    </div>
  );
}
