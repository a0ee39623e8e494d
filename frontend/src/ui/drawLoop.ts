// Drawing at the display's need, not at the screen's frame rate: a chart asks for an
// animation frame only when something new came (its data source calls `kick`), and draws at
// most `maxHz` times a second. An idle HMI page then costs the browser next to nothing (a
// free-running requestAnimationFrame loop kept Chromium at a third of a core doing nothing),
// while data arriving at 50 frames a second is drawn as it comes.

export interface DrawLoop {
  /** Something new to show: draw in the next animation frame (or as soon as `maxHz` allows). */
  kick(): void;
  /** Stop for good (the chart goes). */
  stop(): void;
}

/** Calls `draw` in an animation frame after each `kick`, at most `maxHz` times a second. */
export function drawLoop(draw: (now: number) => void, maxHz: number): DrawLoop {
  // the display draws at its own rate (60 Hz: every 16.7 ms): a frame up to half of one early
  // counts as on time, or 50 a second would come out as 30
  const minMs = 1000 / maxHz - 8;
  let raf = 0;
  let wanted = false;
  let last = -Infinity;
  let stopped = false;
  const frame = (now: number) => {
    raf = 0;
    if (stopped || !wanted) return;
    if (now - last < minMs) {
      raf = requestAnimationFrame(frame); // not yet: the next frame
      return;
    }
    wanted = false;
    last = now;
    draw(now);
  };
  return {
    kick() {
      wanted = true;
      if (!raf && !stopped) raf = requestAnimationFrame(frame);
    },
    stop() {
      stopped = true;
      if (raf) cancelAnimationFrame(raf);
    },
  };
}
