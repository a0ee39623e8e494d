// Inject a fault into one seat, the selected seats or the whole class: the kind from the
// catalogue, its fields (range and unit from the schema), the seat's axes, and when it
// takes effect (now, after some simulated seconds, or on the axis' next motion).
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { ClassInfo, FaultInject, Refusal } from "../api/types";
import { injectClass, injectSeat, seats } from "../state/classes";
import { Panel } from "../ui/Panel";
import { codeSpans } from "../ui/codeSpans";
import { RefusalLine } from "../ui/useCommand";
import { faultCatalogue, rangeText, type FaultKind } from "./faultCatalogue";
import { faultFor } from "./uiState";

type When = "now" | "after" | "motion";

export function FaultForm(props: { c: ClassInfo; target: number[] }) {
  const { c, target } = props;
  const [kinds, setKinds] = useState<FaultKind[]>([]);
  const [kind, setKind] = useState("");
  const [values, setValues] = useState<Record<string, string>>({});
  const [when, setWhen] = useState<When>("now");
  const [afterS, setAfterS] = useState("5");
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  useEffect(() => {
    faultCatalogue().then(
      (k) => {
        setKinds(k);
        setKind((was) => was || k[0]?.kind || "");
      },
      (e: unknown) => setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] }),
    );
  }, []);
  const first = seats.value.find((s) => s.n === (target[0] ?? 1));
  const axes = first?.frame.value.axes.map((a) => a.name) ?? [];
  const spec = kinds.find((k) => k.kind === kind);
  const value = (name: string, fallback = "") => values[name] ?? fallback;
  const set = (name: string) => (e: Event) => setValues({ ...values, [name]: (e.target as HTMLInputElement).value });
  const single = target.length === 1 ? c.seats.find((s) => s.n === target[0]) : undefined;
  const who = single ? `seat ${single.n} (${single.student})` : target.length ? `seats ${target.join(", ")}` : "the whole class";

  async function submit(e: Event) {
    e.preventDefault();
    if (!spec) return;
    const fault: Record<string, string | number> = { kind: spec.kind };
    for (const f of spec.fields) {
      const v = value(f.name, f.type === "axis" ? axes[0] ?? "" : f.default?.toString() ?? "");
      if (v.trim() === "" && !f.required) continue;
      if (v.trim() === "" || (f.type !== "axis" && !Number.isFinite(Number(v)))) {
        setRefusal({ message: `${f.name}: give ${f.type === "axis" ? "an axis" : "a number"}`, problems: [] });
        return;
      }
      fault[f.name] = f.type === "axis" ? v : Number(v);
    }
    const inject = {
      fault,
      trigger: { after_s: when === "now" ? 0 : Number(afterS), on_motion: when === "motion" },
    } as unknown as FaultInject; // its shape is the schema's; the service checks it (422)
    setBusy(true);
    try {
      if (single) await injectSeat(single.machine, inject);
      else await injectClass(c.id, target, inject);
      faultFor.value = null;
    } catch (err) {
      setRefusal(err instanceof ApiError ? err.refusal : { message: String(err), problems: [] });
    } finally {
      setBusy(false);
    }
  }
  return (
    <div class="console-dialog" role="dialog" aria-modal="true" aria-label="Inject a fault">
      <Panel id="fault-form" title={`Inject a fault: ${who}`}
        actions={<button type="button" class="secondary" data-testid="fault-cancel" onClick={() => (faultFor.value = null)}>Close</button>}>
        <form class="fault-form" noValidate onSubmit={(e) => void submit(e)}>
          <label>
            Fault
            <select value={kind} data-testid="fault-kind" onChange={(e) => { setKind((e.target as HTMLSelectElement).value); setValues({}); }}>
              {kinds.map((k) => (
                <option key={k.kind} value={k.kind}>{k.title}</option>
              ))}
            </select>
          </label>
          {!kinds.length && !refusal ? <p class="hint" data-testid="fault-loading">loading the fault catalogue…</p> : null}
          {spec ? <p class="fault-what" data-testid="fault-description">{codeSpans(spec.description)}</p> : null}
          {spec?.fields.map((f) => (
            <label key={f.name}>
              <span class="mono">{f.name}</span>
              {f.type === "axis" ? (
                <select value={value(f.name, axes[0] ?? "")} data-testid={`fault-field-${f.name}`} onChange={set(f.name)}>
                  {axes.map((a) => (
                    <option key={a} value={a}>{a}</option>
                  ))}
                </select>
              ) : (
                <input type="number" step={f.type === "integer" ? 1 : "any"} min={f.exclusiveMin ? undefined : f.min} max={f.max}
                  required={f.required} value={value(f.name, f.default?.toString() ?? "")} data-testid={`fault-field-${f.name}`} onInput={set(f.name)} />
              )}
              <span class="hint">
                {f.type === "axis" ? "the seat's axes and spindles" : codeSpans(f.description)}
                {rangeText(f) ? ` · ${rangeText(f)}` : ""}
              </span>
            </label>
          ))}
          <fieldset class="trigger">
            <legend>Takes effect</legend>
            {(
              [
                ["now", "now"],
                ["after", "after … s (simulated)"],
                ["motion", "on the axis' next motion, then after … s"],
              ] as const
            ).map(([w, text]) => (
              <label key={w} class="inline">
                <input type="radio" name="when" checked={when === w} data-testid={`fault-when-${w}`} onChange={() => setWhen(w)} /> {text}
              </label>
            ))}
            <label class="inline">
              <input type="number" min={0} max={86400} step="any" value={afterS} disabled={when === "now"} data-testid="fault-after"
                onInput={(e) => setAfterS((e.target as HTMLInputElement).value)} aria-label="delay, simulated seconds" /> s
            </label>
          </fieldset>
          <p class="hint">The student's screens do not show the fault; the console does.</p>
          <div class="form-buttons">
            <button type="submit" disabled={busy || !spec} data-testid="fault-inject">Inject into {who}</button>
          </div>
          <RefusalLine refusal={refusal} id="fault-refusal" />
        </form>
      </Panel>
    </div>
  );
}
