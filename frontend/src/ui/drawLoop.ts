// Drawing at the display's need, not at the screen's frame rate: a chart asks for an
// animation frame only when it has something new to show, and at most `maxHz` times a
// second. An idle HMI page then costs the browser next to nothing (a free-running
// requestAnimationFrame loop kept Chromium at a third of a core doing nothing).

/** Calls `draw` in an animation frame whenever `due()` says there is something new, at most
 * `maxHz` times a second; returns the function that stops it. */
export function drawLoop(due: () => boolean, draw: (now: number) => void, maxHz: number): () => void {
  let raf = 0;
  const frame = (now: number) => {
    raf = 0;
    draw(now);
  };
  const timer = window.setInterval(() => {
    if (!raf && due()) raf = requestAnimationFrame(frame);
  }, 1000 / maxHz);
  return () => {
    window.clearInterval(timer);
    if (raf) cancelAnimationFrame(raf);
  };
}
