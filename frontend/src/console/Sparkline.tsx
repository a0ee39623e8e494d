// A seat's lag or speed over the last minute: a plain SVG polyline (50 tiles × 4 frames a
// second: no chart library per tile). Lag is drawn around zero, speed from zero up; the scale
// grows with the data and never below `floor`, so noise does not fill the box.
import { HISTORY_S, type Series } from "../state/classes";

const W = 120;
const H = 26;

export function Sparkline(props: { series: Series | undefined; now: number; symmetric: boolean; floor: number; bad?: boolean }) {
  const { series: s, now, symmetric, floor } = props;
  let points = "";
  if (s && s.size) {
    let top = floor;
    for (let k = 0; k < s.size; k++) top = Math.max(top, Math.abs(s.v[s.at(k)]));
    const y = symmetric ? (v: number) => H / 2 - (v / top) * (H / 2 - 1) : (v: number) => H - 1 - (Math.abs(v) / top) * (H - 2);
    const parts: string[] = [];
    for (let k = 0; k < s.size; k++) {
      const i = s.at(k);
      const age = now - s.t[i];
      if (age > HISTORY_S) continue;
      parts.push(`${(W - (age / HISTORY_S) * W).toFixed(1)},${y(s.v[i]).toFixed(1)}`);
    }
    points = parts.join(" ");
  }
  return (
    <svg class={props.bad ? "spark bad" : "spark"} viewBox={`0 0 ${W} ${H}`} width={W} height={H} aria-hidden="true">
      {symmetric ? <line x1="0" x2={W} y1={H / 2} y2={H / 2} class="zero" /> : null}
      <polyline points={points} />
    </svg>
  );
}
