// The gear range table as bars on one speed scale, the active stage highlighted and the
// programmed speed marked.
export interface GearRange {
  min: number;
  max: number;
}

export function GearBars(props: { ranges: GearRange[]; active: number | null; speed: number | null }) {
  const top = Math.max(1, ...props.ranges.map((r) => r.max)) * 1.05;
  const W = 360;
  const ROW = 18;
  const x = (v: number) => 40 + (v / top) * (W - 50);
  const H = props.ranges.length * ROW + 18;
  const s = props.speed;
  return (
    <svg
      class="gearbars"
      viewBox={`0 0 ${W} ${H}`}
      role="img"
      aria-label={`gear ranges, programmed speed ${s ?? "none"} rpm`}
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
              <title>{`M${39 + g}: ${r.min}–${r.max} rpm`}</title>
            </rect>
          </g>
        );
      })}
      {s !== null ? (
        <g data-testid="gear-mark" data-rpm={s}>
          <line x1={x(s)} x2={x(s)} y1="0" y2={H - 14} class="mark" />
          <text x={x(s)} y={H - 3} class="mark-label" text-anchor="middle">
            S{Math.round(s)}
          </text>
        </g>
      ) : null}
    </svg>
  );
}
