// Several live plots side by side (their configuration and subscription: state/plots.ts).
import { defaultPlots, plots as plotsSignal, setPlots } from "../state/plots";
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
