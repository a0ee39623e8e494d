// A lamp: colour, a filled/hollow mark and text, so colour is never the only signal.
type Tone = "ok" | "warn" | "bad" | "info";

export function Lamp(props: { on: boolean | null | undefined; label: string; tone?: Tone; id?: string; title?: string }) {
  const on = !!props.on;
  const tone = props.tone ?? "ok";
  return (
    <span
      class={`lamp ${on ? `on ${tone}` : "off"}`}
      data-testid={props.id}
      data-on={on ? "1" : "0"}
      title={props.title}
      role="status"
      aria-label={`${props.label}: ${on ? "on" : "off"}`}
    >
      <span class="mark" aria-hidden="true">
        {on ? "●" : "○"}
      </span>
      {props.label}
    </span>
  );
}
