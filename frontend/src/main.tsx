import { effect } from "@preact/signals";
import { render } from "preact";
import { App } from "./App";
import { fps } from "./panels/LivePlot";
import { loadMe, loggedIn } from "./state/auth";
import { endSession, startSession } from "./state/session";
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
// the machines and their socket run only while someone is logged in (logged out, nothing asks)
effect(() => {
  if (loggedIn.value) void startSession();
  else endSession();
});
void loadMe();
