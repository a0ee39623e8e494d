// The stored programs: open one, start a new one, delete one (after a confirmation).
import { useState } from "preact/hooks";
import type { ProgramInfo } from "../api/types";
import { may } from "../state/control";

export function ProgramList(props: {
  programs: ProgramInfo[];
  open: string | null;
  onOpen: (name: string) => void;
  onNew: () => void;
  onDelete: (name: string) => void;
}) {
  const [confirm, setConfirm] = useState<string | null>(null);
  const writer = may("programs");
  return (
    <div class="prog-list" data-testid="program-list">
      <div class="row">
        <b>Programs</b>
        <button type="button" class="secondary" data-testid="program-new" onClick={props.onNew}>
          New
        </button>
      </div>
      {props.programs.length ? null : <p class="hint">No stored programs yet.</p>}
      <ul>
        {props.programs.map((p) => (
          <li key={p.name} class={p.name === props.open ? "open" : ""} data-testid={`program-item-${p.name}`}>
            <button type="button" class="link" data-testid={`program-open-${p.name}`} onClick={() => props.onOpen(p.name)}
              title={`${p.lines} lines, ${p.size} characters; saved ${new Date(p.updated_at).toLocaleString()} by ${p.updated_by}`}>
              {p.name}
            </button>
            <span class="hint">{p.lines} lines</span>
            {confirm === p.name ? (
              <span class="row-actions" role="alert" data-testid="program-delete-ask">
                Delete {p.name}?
                <button type="button" class="stop" data-testid="program-delete-confirm"
                  onClick={() => (setConfirm(null), props.onDelete(p.name))}>
                  Delete
                </button>
                <button type="button" class="secondary" onClick={() => setConfirm(null)}>
                  Keep
                </button>
              </span>
            ) : (
              <button type="button" class="link" data-testid={`program-delete-${p.name}`} aria-label={`delete ${p.name}`}
                disabled={!writer} title={writer ? "delete this program" : "your role may not delete programs"}
                onClick={() => setConfirm(p.name)}>
                ✕
              </button>
            )}
          </li>
        ))}
      </ul>
    </div>
  );
}
