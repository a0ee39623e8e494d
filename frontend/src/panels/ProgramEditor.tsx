// The program text: a textarea with a line-number gutter kept in scroll sync, the line of a
// syntax error marked (with a caret at its column) and the block the channel runs highlighted.
import { useEffect, useRef, useState } from "preact/hooks";

const LINE_PX = 18; // as .prog-editor's line-height
const PAD_PX = 6; // as .prog-editor textarea's padding

export interface Mark {
  line: number;
  column?: number;
}

export function ProgramEditor(props: {
  text: string;
  onInput: (text: string) => void;
  error: Mark | null;
  running: number | null; // the block line the channel is in
  readOnly?: boolean;
}) {
  const [scroll, setScroll] = useState({ top: 0, left: 0 });
  const area = useRef<HTMLTextAreaElement>(null);
  useEffect(() => {
    // keep the running block in view (as the operator follows the program)
    const t = area.current;
    const line = props.running;
    if (!t || !line) return;
    const y = (line - 1) * LINE_PX;
    if (y < t.scrollTop || y + LINE_PX > t.scrollTop + t.clientHeight - 2 * PAD_PX) t.scrollTop = Math.max(0, y - t.clientHeight / 3);
  }, [props.running]);
  const lines = props.text.split("\n").length;
  const numbers = Array.from({ length: lines }, (_, i) => i + 1).join("\n");
  const band = (m: Mark, cls: string, id: string) => (
    <div class={cls} data-testid={id} data-line={m.line}
      style={{ top: `${PAD_PX + (m.line - 1) * LINE_PX - scroll.top}px`, height: `${LINE_PX}px` }}>
      {m.column ? (
        <span class="prog-caret" style={{ left: `calc(${PAD_PX - scroll.left}px + ${m.column - 1}ch)` }}>▲</span>
      ) : null}
    </div>
  );
  return (
    <div class="prog-editor">
      <pre class="prog-gutter" aria-hidden="true" style={{ transform: `translateY(${-scroll.top}px)` }}>
        {numbers}
      </pre>
      <div class="prog-text">
        <div class="prog-marks" aria-hidden="true">
          {props.running ? band({ line: props.running }, "prog-running", "program-running-line") : null}
          {props.error ? band(props.error, "prog-error", "program-error-line") : null}
        </div>
        <textarea
          ref={area}
          data-testid="program-text"
          aria-label="program text"
          spellcheck={false}
          wrap="off"
          autocomplete="off"
          readOnly={props.readOnly}
          value={props.text}
          onInput={(e) => props.onInput((e.target as HTMLTextAreaElement).value)}
          onScroll={(e) => {
            const t = e.target as HTMLTextAreaElement;
            setScroll({ top: t.scrollTop, left: t.scrollLeft });
          }}
        />
      </div>
    </div>
  );
}
