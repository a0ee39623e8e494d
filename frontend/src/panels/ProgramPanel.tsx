// The program workspace: stored programs, the editor (checked on the machine as one types),
// save, upload and download, the channel (load, cycle start, feedhold, single block, stop)
// and the tool path, commanded and actual.
import { useEffect, useRef, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Command, ProgramInfo, ProgramPreview, Refusal } from "../api/types";
import { may } from "../state/control";
import {
  PROGRAM_NAME,
  deleteProgram,
  listPrograms,
  nameFromFile,
  previewProgram,
  readProgram,
  writeProgram,
} from "../state/programs";
import { machineId, status } from "../state/session";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { ChannelControls } from "./ChannelControls";
import { ProgramEditor } from "./ProgramEditor";
import { ProgramList } from "./ProgramList";
import { ToolpathPlot } from "./ToolpathPlot";

const CHECK_MS = 300; // the program is checked once typing pauses this long
const EXAMPLE = "; a new program\nG18 G90\nG00 X40 Z5\nG01 Z-20 F300\nG02 X50 Z-25 K0 I5\nG00 X80 Z5\nM30\n";

const refusalOf = (e: unknown): Refusal => (e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });

export function ProgramPanel() {
  const [programs, setPrograms] = useState<ProgramInfo[]>([]);
  const [name, setName] = useState("new_program.nc");
  const [text, setText] = useState(EXAMPLE);
  const [saved, setSaved] = useState<string | null>(null); // the text as stored under `name`
  const [preview, setPreview] = useState<ProgramPreview | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [note, setNote] = useState("");
  const file = useRef<HTMLInputElement>(null);
  const ask = useRef(0);

  const refresh = () =>
    listPrograms()
      .then(setPrograms)
      .catch((e) => setRefusal(refusalOf(e)));
  useEffect(() => void refresh(), []);

  // check and draw the program on this machine as one types
  useEffect(() => {
    const n = ++ask.current;
    if (!text.trim() || !machineId.value) {
      setPreview(null);
      return;
    }
    const t = setTimeout(() => {
      previewProgram(text)
        .then((p) => n === ask.current && setPreview(p))
        .catch((e) => n === ask.current && setRefusal(refusalOf(e)));
    }, CHECK_MS);
    return () => clearTimeout(t);
  }, [text, machineId.value]);

  async function open(n: string) {
    try {
      const p = await readProgram(n);
      setName(p.name);
      setText(p.text);
      setSaved(p.text);
      setRefusal(null);
      setNote(`opened ${p.name}`);
    } catch (e) {
      setRefusal(refusalOf(e));
    }
  }

  async function save() {
    try {
      const info = await writeProgram(name, text);
      setSaved(text);
      setRefusal(null);
      setNote(`saved ${info.name} (${info.lines} lines)`);
      await refresh();
    } catch (e) {
      setRefusal(refusalOf(e));
    }
  }

  async function remove(n: string) {
    try {
      await deleteProgram(n);
      if (n === name) setSaved(null);
      setNote(`deleted ${n}`);
      await refresh();
    } catch (e) {
      setRefusal(refusalOf(e));
    }
  }

  async function upload(f: File) {
    setName(nameFromFile(f.name));
    setText(await f.text());
    setSaved(null);
    setNote(`read ${f.name}: not saved yet`);
  }

  function download() {
    const a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([text], { type: "text/plain" }));
    a.download = /\.(nc|ngc)$/i.test(name) ? name : `${name}.nc`;
    a.click();
    setTimeout(() => URL.revokeObjectURL(a.href), 1000);
  }

  const badName = PROGRAM_NAME.test(name) ? "" : "a name of letters, digits, _ . - (up to 64, not starting with . or -)";
  const dirty = saved !== text;
  const writer = may("programs");
  const ch = status.value?.channel;
  const loaded = ch?.program === name && ch?.state !== "idle";
  // the stored program by name when the editor shows it unchanged, else the editor's text
  const load: Command | null = badName ? null : dirty ? { type: "program_load", name, text } : { type: "program_load", name };
  const err = preview?.error ?? null;
  return (
    <Panel title="Program" id="program">
      <div class="program">
        <ProgramList programs={programs} open={saved !== null ? name : null} onOpen={(n) => void open(n)}
          onNew={() => (setName("new_program.nc"), setText(EXAMPLE), setSaved(null), setNote(""))} onDelete={(n) => void remove(n)} />
        <div class="prog-main">
          <div class="row">
            <label>
              Name{" "}
              <input data-testid="program-name" value={name} aria-invalid={!!badName} title={badName}
                onInput={(e) => setName((e.target as HTMLInputElement).value)} />
            </label>
            <button type="button" data-testid="program-save" disabled={!!badName || !writer}
              title={writer ? badName || "store the program under this name" : "your role may not write programs"} onClick={() => void save()}>
              Save{dirty ? " *" : ""}
            </button>
            <button type="button" class="secondary" data-testid="program-upload-button" onClick={() => file.current?.click()}>
              Upload…
            </button>
            <input ref={file} type="file" accept=".nc,.ngc,.txt,text/plain" data-testid="program-upload" hidden
              onChange={(e) => {
                const f = (e.target as HTMLInputElement).files?.[0];
                if (f) void upload(f);
                (e.target as HTMLInputElement).value = "";
              }} />
            <button type="button" class="secondary" data-testid="program-download" onClick={download}>
              Download .nc
            </button>
            <span class="hint" data-testid="program-note">{note}</span>
          </div>
          <ProgramEditor text={text} onInput={setText} error={err} running={loaded && ch?.state !== "ready" ? (ch?.block_line ?? null) : null} />
          {err ? (
            <p class="refusal" role="alert" data-testid="program-error" data-line={err.line} data-column={err.column}>
              line {err.line}, column {err.column}: {err.message} ({err.code})
            </p>
          ) : (
            <p class="hint" data-testid="program-ok">{preview ? `no errors: ${preview.segments.length} moves` : "checking…"}</p>
          )}
          <RefusalLine refusal={refusal} id="program-store-refusal" />
          <ChannelControls load={load} canLoad={badName} />
        </div>
        <ToolpathPlot preview={preview} blockLine={loaded ? (ch?.block_line ?? null) : null} />
      </div>
    </Panel>
  );
}
