// The gear range table as bars on one rpm scale (ticks with numbers), the active stage
// highlighted and the programmed speed marked; each bar names its M function, gear number and
// gear record (M40 · gear 1 · getriebe[0]).
import { gearName, niceTicks } from "../ui/format";

export interface GearRange {
  min: number;
  max: number;
}

export function GearBars(props: { ranges: GearRange[]; active: number | null; speed: number | null }) {
  const ticks = niceTicks(Math.max(1, ...props.ranges.map((r) => r.max)));
  const top = ticks[ticks.length - 1];
  const W = 360;
  const ROW = 18;
  const LEFT = 40;
  const x = (v: number) => LEFT + (v / top) * (W - LEFT - 14);
  const bars = props.ranges.length * ROW;
  const H = bars + 34; // the scale, then the programmed speed's label
  const s = props.speed;
  return (
    <svg
      class="gearbars"
      viewBox={`0 0 ${W} ${H}`}
      role="img"
      aria-label={`gear ranges on an rpm scale, programmed speed ${s ?? "none"} rpm`}
      data-testid="gear-bars"
    >
      {props.ranges.map((r, i) => {
        const g = i + 1;
        const on = g === props.active;
        const holds = s !== null && s >= r.min && s <= r.max;
        return (
          <g key={g} data-testid={`gear-bar-${g}`} data-active={on ? "1" : "0"} data-holds={holds ? "1" : "0"}>
            <text x="2" y={i * ROW + 13} class={on ? "bar-label active" : "bar-label"}>
              M{39 + g}
            </text>
            <rect
              x={x(r.min)}
              y={i * ROW + 3}
              width={Math.max(1, x(r.max) - x(r.min))}
              height={ROW - 6}
              class={on ? "bar active" : "bar"}
            >
              <title>{`${gearName(g)}: ${r.min}–${r.max} rpm`}</title>
            </rect>
          </g>
        );
      })}
      <g class="gear-axis" data-testid="gear-bars-scale" data-ticks={ticks.join(" ")}>
        <line x1={x(0)} x2={x(top)} y1={bars + 2} y2={bars + 2} class="axis" />
        {ticks.map((v, k) => (
          <g key={v}>
            <line x1={x(v)} x2={x(v)} y1={bars + 2} y2={bars + 6} class="axis" />
            <text x={x(v) + (k === ticks.length - 1 ? 12 : 0)} y={bars + 16} class="tick-label"
              text-anchor={k === 0 ? "start" : k === ticks.length - 1 ? "end" : "middle"}>
              {k === ticks.length - 1 ? `${v} rpm` : v}
            </text>
          </g>
        ))}
      </g>
      {s !== null ? (
        <g data-testid="gear-mark" data-rpm={s}>
          <line x1={x(s)} x2={x(s)} y1="0" y2={bars + 6} class="mark" />
          <text x={x(s)} y={H - 3} class="mark-label" text-anchor="middle">
            S{Math.round(s)}
          </text>
        </g>
      ) : null}
    </svg>
  );
}
