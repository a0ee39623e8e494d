// The scope workspace's command strip: the spindle's keys (M3 S…, M4, M5, M19) and an MDI line,
// so a capture can be triggered without leaving the scope. The same components as the spindle
// and MDI panels (SpindleKeys, MdiLine): one set of checks and commands.
import { useState } from "preact/hooks";
import { status } from "../state/session";
import { Panel } from "../ui/Panel";
import { RefusalLine, useCommand } from "../ui/useCommand";
import { MdiLine, withBlock } from "./MdiPanel";
import { SpindleKeys } from "./SpindleKeys";

export function CommandStrip() {
  const sp = status.value?.axes.find((a) => a.kind === "spindle");
  const cmd = useCommand();
  const [line, setLine] = useState("");
  const [history, setHistory] = useState<string[]>([]);
  return (
    <Panel title={sp ? `Commands · spindle ${sp.name}` : "Commands"} id="scope-commands">
      <div class="command-strip">
        {sp ? (
          <div class="strip-spindle">
            <SpindleKeys sp={sp} run={cmd.run} />
          </div>
        ) : null}
        <div class="strip-mdi">
          <MdiLine line={line} setLine={setLine} history={history} onSent={(b) => setHistory((h) => withBlock(h, b))} />
        </div>
      </div>
      <RefusalLine refusal={cmd.refusal} id="strip-refusal" />
    </Panel>
  );
}
