// Several live plots side by side (their configuration and subscription: state/plots.ts).
import { PLOT_RATES, defaultPlots, plotRate, plots as plotsSignal, setPlotRate, setPlots } from "../state/plots";
import { catalogue } from "../state/telemetry";
import { Panel } from "../ui/Panel";
import { LivePlot } from "./LivePlot";

export function Plots(props: { single?: boolean }) {
  const plots = plotsSignal.value;
  const cat = catalogue.value;
  const update = setPlots;

  const shown = props.single ? plots.slice(0, 1) : plots;
  return (
    <Panel
      title={props.single ? "Live plot" : "Live plots"}
      id={props.single ? "plot" : "plots"}
      actions={
        <span class="row">
          <label title="how often the plots redraw: lower spares a slow computer or a remote desktop">
            Refresh{" "}
            <select data-testid="plot-rate" value={plotRate.value}
              onChange={(e) => setPlotRate(Number((e.target as HTMLSelectElement).value))}>
              {PLOT_RATES.map((r) => (
                <option key={r} value={r}>
                  {r}/s
                </option>
              ))}
            </select>
          </label>
          {props.single ? null : (
            <>
              <button type="button" data-testid="plot-add"
                onClick={() => update([...plots, { id: `p${Date.now()}`, signals: [], windowS: 10 }])}>
                + Add plot
              </button>
              <button type="button" class="link" onClick={() => update(defaultPlots(cat))}>
                defaults
              </button>
            </>
          )}
        </span>
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
