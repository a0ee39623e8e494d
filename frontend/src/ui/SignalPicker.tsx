// A drop-down of every signal grouped by axis, with a checkbox each (plots and the scope);
// the scope's drive-rate capture offers the drive signals instead.
import { catalogue } from "../state/telemetry";

export interface PickableSignal {
  name: string;
  axis: string;
}

/** An open picker that would run past the window's right edge moves left until it fits (the
 * right-hand plot's picker was cut off, and the page does not scroll sideways). */
function keepInWindow(e: Event): void {
  const d = e.currentTarget as HTMLDetailsElement;
  const body = d.querySelector<HTMLElement>(".picker-body");
  if (!body || !d.open) return;
  body.style.left = "";
  const over = body.getBoundingClientRect().right - (document.documentElement.clientWidth - 8);
  if (over > 0) body.style.left = `${-over}px`;
}

export function SignalPicker(props: {
  chosen: string[];
  onChange: (names: string[]) => void;
  max?: number;
  testid?: string;
  signals?: PickableSignal[];
}) {
  const { chosen, max } = props;
  const names = props.signals ?? catalogue.value;
  const axes = [...new Set(names.map((s) => s.axis))];
  const full = max !== undefined && chosen.length >= max;
  return (
    <details class="signal-picker" data-testid={props.testid} onToggle={keepInWindow}>
      <summary>
        Signals ({chosen.length}
        {max !== undefined ? ` of ≤ ${max}` : ""})
      </summary>
      <div class="picker-body">
        {axes.map((a) => (
          <fieldset key={a}>
            <legend>{a}</legend>
            {names
              .filter((s) => s.axis === a)
              .map((s) => {
                const on = chosen.includes(s.name);
                return (
                  <label key={s.name}>
                    <input
                      type="checkbox"
                      data-signal={s.name}
                      checked={on}
                      disabled={!on && full}
                      onChange={(e) =>
                        props.onChange((e.target as HTMLInputElement).checked ? [...chosen, s.name] : chosen.filter((n) => n !== s.name))
                      }
                    />
                    {s.name.slice(a.length + 1)}
                  </label>
                );
              })}
          </fieldset>
        ))}
      </div>
    </details>
  );
}
