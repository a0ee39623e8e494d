// The live plots of the machine on screen: their choice of signals (per machine; survives a
// reload, localStorage) and their subscription. The subscription is the plots' whether a plot
// is on screen or not, so their rings keep filling while another workspace is open and the
// history is there when the plots are shown again.
import { effect, signal } from "@preact/signals";
import type { SignalInfo } from "../api/types";
import { machineId } from "./session";
import { catalogue, setFramePeriod, want } from "./telemetry";

export interface PlotConfig {
  id: string;
  signals: string[];
  windowS: number;
  /** one y axis per unit instead of one per quantity */
  shareY?: boolean;
}

/** Spindle speed command vs actual, and the lag of the linear axes. */
export function defaultPlots(signals: SignalInfo[]): PlotConfig[] {
  const names = signals.map((s) => s.name);
  const speed = names.filter((n) => /\.speed_(cmd|act)_rpm$/.test(n)).slice(0, 2);
  const lag = names.filter((n) => /\.lag_mm$/.test(n));
  return [
    { id: "p1", signals: speed, windowS: 10 },
    { id: "p2", signals: lag, windowS: 10 },
  ].filter((p) => p.signals.length);
}

const storageKey = () => `inbetrieb.plots.${machineId.value}`;

/** The plots of the machine on screen, first the one the Operate workspace shows. */
export const plots = signal<PlotConfig[]>([]);

/** Change the plots (and keep the change). */
export function setPlots(next: PlotConfig[]): void {
  plots.value = next;
  localStorage.setItem(storageKey(), JSON.stringify(next));
}

effect(() => {
  const cat = catalogue.value;
  if (!machineId.value || !cat.length) return;
  const known = new Set(cat.map((s) => s.name));
  let saved: PlotConfig[] | null = null;
  try {
    saved = JSON.parse(localStorage.getItem(storageKey()) ?? "null") as PlotConfig[] | null;
  } catch {
    saved = null;
  }
  const valid = saved?.map((p) => ({ ...p, signals: p.signals.filter((s) => known.has(s)) }));
  plots.value = valid?.length ? valid : defaultPlots(cat);
});

effect(() => want("plots", [...new Set(plots.value.flatMap((p) => p.signals))]));

/** How often a live plot may redraw, per second: 50 draws every telemetry frame; 25 and 10 spare
 * a slow computer or a remote desktop (the samples are all drawn, only less often). Kept in this
 * browser for every machine. */
export const PLOT_RATES = [50, 25, 10] as const;
const RATE_KEY = "inbetrieb.plotRate";

function savedRate(): number {
  const r = Number(localStorage.getItem(RATE_KEY));
  return (PLOT_RATES as readonly number[]).includes(r) ? r : PLOT_RATES[0];
}

export const plotRate = signal<number>(savedRate());

/** Change how often the live plots redraw (and keep it). */
export function setPlotRate(perS: number): void {
  plotRate.value = perS;
  localStorage.setItem(RATE_KEY, String(perS));
}

effect(() => setFramePeriod(1 / plotRate.value));
