import { render } from "preact";
import { App } from "./App";
import { fps } from "./panels/LivePlot";
import { startSession } from "./state/session";
import type { Rings } from "./state/rings";
import { frameListeners, frames, rings } from "./state/telemetry";
import "./styles.css";

declare global {
  interface Window {
    inbetrieb: {
      fps: typeof fps;
      frames: typeof frames;
      frameListeners: typeof frameListeners;
      rings: () => Rings;
    };
  }
}
// counters and hooks for bench/ui.py
window.inbetrieb = { fps, frames, frameListeners, rings: () => rings.value };

render(<App />, document.getElementById("app")!);
void startSession();
