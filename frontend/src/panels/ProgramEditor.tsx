// The program text: a textarea with a line-number gutter kept in scroll sync, the line of a
// syntax error marked (the character at its column boxed) and the block the channel runs
// highlighted. The marks are a layer of text laid out like the textarea (one CSS rule,
// .prog-metrics, gives both their font, line height and padding): a mark is the line's own
// text up to the column, invisible, so it lands where the textarea draws that character,
// whatever the font, tabs or zoom.
import { useEffect, useRef, useState } from "preact/hooks";

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
    const linePx = parseFloat(getComputedStyle(t).lineHeight) || 18;
    const y = (line - 1) * linePx;
    if (y < t.scrollTop || y + 2 * linePx > t.scrollTop + t.clientHeight) t.scrollTop = Math.max(0, y - t.clientHeight / 3);
  }, [props.running]);
  const textLines = props.text.split("\n");
  const numbers = textLines.map((_, i) => i + 1).join("\n");
  const shift = { transform: `translate(${-scroll.left}px, ${-scroll.top}px)` };
  // one row of the mark layer: blank rows before it keep it on its line
  const band = (m: Mark, cls: string, id: string) => {
    const line = textLines[m.line - 1] ?? "";
    const col = m.column && m.column > 0 ? m.column : 0;
    return (
      <div class="prog-metrics prog-layer" data-testid={id} data-line={m.line} style={shift}>
        {"\n".repeat(m.line - 1)}
        <span class={`prog-band ${cls}`}>
          {col ? (
            <>
              <span class="prog-ghost">{line.slice(0, col - 1)}</span>
              <span class="prog-caret" data-testid={`${id}-caret`} data-column={col}>{line.charAt(col - 1) || " "}</span>
            </>
          ) : (
            " "
          )}
        </span>
      </div>
    );
  };
  return (
    <div class="prog-editor">
      <pre class="prog-gutter prog-metrics" aria-hidden="true" style={{ transform: `translateY(${-scroll.top}px)` }}>
        {numbers}
      </pre>
      <div class="prog-text">
        <div class="prog-marks" aria-hidden="true">
          {props.running ? band({ line: props.running }, "prog-running", "program-running-line") : null}
          {props.error ? band(props.error, "prog-error", "program-error-line") : null}
        </div>
        <textarea
          ref={area}
          class="prog-metrics"
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
