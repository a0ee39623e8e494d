// Several live plots side by side; their choice of signals survives a reload (localStorage).
import { useEffect, useState } from "preact/hooks";
import type { SignalInfo } from "../api/types";
import { machineId } from "../state/session";
import { catalogue } from "../state/telemetry";
import { Panel } from "../ui/Panel";
import { LivePlot, type PlotConfig } from "./LivePlot";

/** Spindle speed command vs actual, and the lag of the linear axes. */
export function defaultPlots(signals: SignalInfo[]): PlotConfig[] {
  const names = signals.map((s) => s.name);
  const speed = names.filter((n) => /\.speed_(cmd|act)_rpm$/.test(n)).slice(0, 2);
  const lag = names.filter((n) => /\.lag_mm$/.test(n));
  return [
    { id: "p1", signals: speed, windowS: 10 },
    { id: "p2", signals: lag, windowS: 10 },
  ].filter((p) => p.signals.length);
}

const storageKey = () => `inbetrieb.plots.${machineId.value}`;

export function Plots(props: { single?: boolean }) {
  const [plots, setPlots] = useState<PlotConfig[]>([]);
  const cat = catalogue.value;
  useEffect(() => {
    if (!cat.length) return;
    const known = new Set(cat.map((s) => s.name));
    let saved: PlotConfig[] | null = null;
    try {
      saved = JSON.parse(localStorage.getItem(storageKey()) ?? "null") as PlotConfig[] | null;
    } catch {
      saved = null;
    }
    const valid = saved?.map((p) => ({ ...p, signals: p.signals.filter((s) => known.has(s)) }));
    setPlots(valid?.length ? valid : defaultPlots(cat));
  }, [cat, machineId.value]);

  function update(next: PlotConfig[]) {
    setPlots(next);
    localStorage.setItem(storageKey(), JSON.stringify(next));
  }

  const shown = props.single ? plots.slice(0, 1) : plots;
  return (
    <Panel
      title={props.single ? "Live plot" : "Live plots"}
      id={props.single ? "plot" : "plots"}
      actions={
        props.single ? null : (
          <span class="row">
            <button type="button" data-testid="plot-add"
              onClick={() => update([...plots, { id: `p${Date.now()}`, signals: [], windowS: 10 }])}>
              + Add plot
            </button>
            <button type="button" class="link" onClick={() => update(defaultPlots(cat))}>
              defaults
            </button>
          </span>
        )
      }
    >
      <div class={props.single ? "plots single" : "plots"}>
        {shown.map((p, i) => (
          <LivePlot
            key={p.id}
            config={p}
            onChange={(c) => update(plots.map((q, j) => (j === i ? c : q)))}
            onRemove={props.single ? undefined : () => update(plots.filter((_, j) => j !== i))}
          />
        ))}
      </div>
    </Panel>
  );
}
