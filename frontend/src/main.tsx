import { render } from "preact";
import { App } from "./App";
import { fps } from "./panels/LivePlot";
import { startSession } from "./state/session";
import { frames } from "./state/telemetry";
import "./styles.css";

declare global {
  interface Window {
    inbetrieb: { fps: typeof fps; frames: typeof frames };
  }
}
window.inbetrieb = { fps, frames }; // counters for bench/ui.py and the browser tests

render(<App />, document.getElementById("app")!);
void startSession();
