import type { ComponentChildren } from "preact";

export function Panel(props: { title: string; id: string; children: ComponentChildren; actions?: ComponentChildren }) {
  return (
    <section class="panel" data-testid={`panel-${props.id}`} aria-labelledby={`h-${props.id}`}>
      <header>
        <h2 id={`h-${props.id}`}>{props.title}</h2>
        {props.actions}
      </header>
      <div class="panel-body">{props.children}</div>
    </section>
  );
}
