// Measurements of one channel over the window between the cursors (or the visible range),
// computed by the service: max |value| (max lag), overshoot, rise time, settling, steady mean.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { Measurements as M, TraceDetail } from "../api/types";
import { measure } from "../state/scope";
import { fmt } from "../ui/format";
import type { Cursors } from "./CaptureChart";

export function Measurements(props: { detail: TraceDetail; cursors: Cursors; range: [number, number] | null }) {
  const { detail, cursors, range } = props;
  const { channel, band } = measure.value;
  const setChannel = (c: string) => measure.patch({ channel: c });
  const setBand = (b: number) => measure.patch({ band: b });
  const [m, setM] = useState<M | null>(null);
  const [error, setError] = useState("");
  const names = detail.channels.map((c) => c.name);
  const ch = names.includes(channel) ? channel : (detail.channels.find((c) => c.kind === "float")?.name ?? names[0]);
  const [a, b] = cursors;
  const win: [number, number] | null = a !== null && b !== null ? [Math.min(a, b), Math.max(a, b)] : range;
  const source = a !== null && b !== null ? "between the cursors" : "visible range";

  useEffect(() => {
    const q = new URLSearchParams({ channel: ch, band_pct: String(band) });
    if (win) {
      q.set("t0_s", String(win[0]));
      q.set("t1_s", String(win[1]));
    }
    const timer = setTimeout(() => {
      http
        .get<M>(`/api/traces/${detail.id}/measure?${q}`)
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
  }, [detail.id, ch, band, win?.[0], win?.[1]]);

  const u = m?.unit ?? "";
  const row = (label: string, id: string, value: string, title = "") => (
    <tr title={title}>
      <th>{label}</th>
      <td data-testid={`meas-${id}`}>{value}</td>
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
          <tbody>
            {row("window", "window", `${fmt(m.t0_s, 3)} … ${fmt(m.t1_s, 3)} s (${m.samples} samples)`)}
            {row("max |value|", "max-abs", `${fmt(m.max_abs, 4)} ${u} at ${fmt(m.t_max_abs_s, 3)} s`, "e.g. the maximum lag")}
            {m.step_found ? null : (
              <tr>
                <td colSpan={2} class="hint" data-testid="meas-no-step">
                  no step stands out of the noise here (or it comes back): no overshoot or rise time
                </td>
              </tr>
            )}
            {row("overshoot", "overshoot", m.overshoot_pct === null ? "—" : `${fmt(m.overshoot_pct, 2)} %`, "beyond the final value, in % of the step")}
            {row("rise time 10–90 %", "rise", m.rise_time_s === null ? "—" : `${fmt(m.rise_time_s * 1000, 1)} ms`)}
            {row("noise σ", "noise", `${fmt(m.noise, 6)} ${u}`, "from neighbouring samples; a step must exceed 10 σ")}
            {row(`settling (±${fmt(m.band, 4)} ${u})`, "settling", m.settling_time_s === null ? "not settled" : `${fmt(m.settling_time_s * 1000, 1)} ms`, "from the trigger until it stays in the band")}
            {row("steady mean", "final", `${fmt(m.final, 4)} ${u}`, "mean of the last 10 % of the window")}
            {row("min / max", "minmax", `${fmt(m.minimum, 4)} / ${fmt(m.maximum, 4)} ${u}`)}
          </tbody>
        </table>
      ) : null}
    </div>
  );
}
