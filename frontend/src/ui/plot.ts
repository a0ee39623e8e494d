// A uPlot chart that follows its box's width at a fixed height, and its end.
import type uPlot from "uplot";

/** Resize `u` with `el`'s width (at least `minWidth`) at `height`; the returned function
 * stops following and destroys the chart (an effect's cleanup). */
export function followWidth(u: uPlot, el: HTMLElement, height: number, minWidth = 300): () => void {
  const ro = new ResizeObserver(() => u.setSize({ width: Math.max(minWidth, el.clientWidth), height }));
  ro.observe(el);
  return () => {
    ro.disconnect();
    u.destroy();
  };
}
