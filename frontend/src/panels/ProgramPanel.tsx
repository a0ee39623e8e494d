// The program workspace: stored programs, the editor (checked on the machine as one types;
// its draft kept per machine, and whether it is what the channel has loaded), save, upload
// and download, the channel (load, cycle start, feedhold, single block, stop)
// and the tool path, commanded and actual.
import { useEffect, useRef, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { ChannelStatus, CommandResult, ProgramInfo, ProgramPreview, Refusal } from "../api/types";
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
import { type Draft, NEW_NAME, NEW_PROGRAM, readDraft, writeDraft } from "../state/programDraft";
import { numbers, paramsVersion } from "../state/params";
import { axisOutline, machineId, send, status } from "../state/session";
import { fmt } from "../ui/format";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { ChannelControls } from "./ChannelControls";
import { type Mark, ProgramEditor } from "./ProgramEditor";
import { ProgramList } from "./ProgramList";
import { ToolpathPlot } from "./ToolpathPlot";

const CHECK_MS = 300; // the program is checked once typing pauses this long

const refusalOf = (e: unknown): Refusal => (e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });

/** How the editor's text stands to the program in the channel. */
function syncOf(draft: Draft, ch: ChannelStatus | undefined): { state: "none" | "loaded" | "edited"; words: string } {
  const inChannel = ch && ch.state !== "idle" ? ch.program : null;
  if (!inChannel) return { state: "none", words: "Not loaded — the channel has no program" };
  const l = draft.loaded;
  if (l && l.name === inChannel && l.text === draft.text) return { state: "loaded", words: `Loaded: ${inChannel}` };
  return { state: "edited", words: `Edited — not loaded (the channel has ${inChannel})` };
}

export function ProgramPanel() {
  const mid = machineId.value;
  const [programs, setPrograms] = useState<ProgramInfo[]>([]);
  const [draft, setDraft] = useState<Draft>(() => readDraft(mid));
  const [preview, setPreview] = useState<ProgramPreview | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [loadMark, setLoadMark] = useState<(Mark & { text: string }) | null>(null); // a refused load's error
  const [note, setNote] = useState("");
  const file = useRef<HTMLInputElement>(null);
  const ask = useRef(0);
  const { name, text, saved } = draft;
  const update = (patch: Partial<Draft>) =>
    setDraft((d) => {
      const next = { ...d, ...patch };
      writeDraft(mid, next);
      return next;
    });
  useEffect(() => setDraft(readDraft(mid)), [mid]); // each machine has its own draft

  const refresh = () =>
    listPrograms()
      .then(setPrograms)
      .catch((e) => setRefusal(refusalOf(e)));
  useEffect(() => void refresh(), []);

  // check and draw the program on this machine as one types
  useEffect(() => {
    const n = ++ask.current;
    if (!text.trim() || !mid) {
      setPreview(null);
      return;
    }
    const t = setTimeout(() => {
      previewProgram(text)
        .then((p) => n === ask.current && setPreview(p))
        .catch((e) => n === ask.current && setRefusal(refusalOf(e)));
    }, CHECK_MS);
    return () => clearTimeout(t);
  }, [text, mid]);

  async function open(n: string) {
    try {
      const p = await readProgram(n);
      update({ name: p.name, text: p.text, saved: p.text });
      setRefusal(null);
      setNote(`opened ${p.name}`);
    } catch (e) {
      setRefusal(refusalOf(e));
    }
  }

  async function save() {
    try {
      const info = await writeProgram(name, text);
      update({ saved: text });
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
      if (n === name) update({ saved: null });
      setNote(`deleted ${n}`);
      await refresh();
    } catch (e) {
      setRefusal(refusalOf(e));
    }
  }

  async function upload(f: File) {
    update({ name: nameFromFile(f.name), text: await f.text(), saved: null });
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
  const sync = syncOf(draft, ch);
  const loaded = sync.state === "loaded"; // the editor shows what the channel runs
  // the stored program by name when the editor shows it unchanged, else the editor's text
  async function load(): Promise<CommandResult> {
    const sent = text;
    try {
      const r = await send(dirty ? { type: "program_load", name, text } : { type: "program_load", name });
      update({ loaded: { name, text: sent } });
      setLoadMark(null);
      return r;
    } catch (e) {
      const r = e instanceof ApiError ? e.refusal : null;
      setLoadMark(r?.line ? { line: r.line, column: r.column ?? undefined, text: sent } : null);
      throw e;
    }
  }
  const err = preview?.error ?? null;
  // the preview's error, else where the channel refused this very text
  const mark: Mark | null = err ?? (loadMark && loadMark.text === text ? loadMark : null);
  return (
    <Panel title="Program" id="program">
      <div class="program">
        <ProgramList programs={programs} open={saved !== null ? name : null} onOpen={(n) => void open(n)}
          onNew={() => (update({ name: NEW_NAME, text: NEW_PROGRAM, saved: null }), setNote(""))} onDelete={(n) => void remove(n)} />
        <div class="prog-main">
          <div class="row">
            <label>
              Name{" "}
              <input data-testid="program-name" value={name} aria-invalid={!!badName} title={badName}
                onInput={(e) => update({ name: (e.target as HTMLInputElement).value })} />
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
          <p class={`prog-sync ${sync.state}`} data-testid="program-sync" data-state={sync.state}>{sync.words}</p>
          <ProgramEditor text={text} onInput={(t) => update({ text: t })} error={mark}
            running={loaded && ch?.state !== "ready" ? (ch?.block_line ?? null) : null} />
          {err ? (
            <p class="refusal" role="alert" data-testid="program-error" data-line={err.line} data-column={err.column}>
              line {err.line}, column {err.column}: {err.message} ({err.code})
            </p>
          ) : (
            <p class="hint" data-testid="program-ok">{preview ? `no errors: ${preview.segments.length} moves` : "checking…"}</p>
          )}
          <RefusalLine refusal={refusal} id="program-store-refusal" />
          <ChannelControls load={badName ? null : load} canLoad={badName} />
        </div>
        <div>
          <KvMismatch />
          <ToolpathPlot preview={preview} blockLine={loaded ? (ch?.block_line ?? null) : null} />
        </div>
      </div>
    </Panel>
  );
}

const KV_APART = 1.02; // kv of the path axes further apart than this: the contour distorts

/** A warning where the path's linear axes have different kv (getriebe[0].kv): each lags by
 * v/kv of its own, so a line between them bows and a circle turns into an ellipse [004 §3.6];
 * the circularity test measures the effective gains and proposes matching them. */
function KvMismatch() {
  const [kv, setKv] = useState<[string, number][]>([]);
  const linear = axisOutline.value.filter((a) => a.kind === "linear").map((a) => a.name);
  const key = linear.join(",");
  useEffect(() => {
    let live = true;
    void Promise.all(linear.map((n) => numbers("axis", n).then((v): [string, number] => [n, (v.get("getriebe[0].kv") ?? 0) / 100]))).then(
      (rows) => live && setKv(rows),
      () => undefined,
    );
    return () => void (live = false);
  }, [machineId.value, paramsVersion.value, key]);
  const gains = kv.filter(([, v]) => v > 0);
  if (gains.length < 2) return null;
  const lo = Math.min(...gains.map(([, v]) => v));
  const hi = Math.max(...gains.map(([, v]) => v));
  if (hi <= lo * KV_APART) return null;
  return (
    <p class="warn-line" data-testid="kv-mismatch" role="note">
      The path axes follow with different gains: {gains.map(([n, v]) => `${n} kv ${fmt(v, 2)} 1/s`).join(", ")}. Each lags
      by v/kv of its own, so a line between them bows off the programmed one and a circle becomes an ellipse. Match kv
      (Drive tuning → Circularity test measures the effective gains and proposes it).
    </p>
  );
}
