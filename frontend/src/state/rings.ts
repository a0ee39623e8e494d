// Sample rings for the live plots: one shared time axis, one ring per signal. Every sample is
// written twice (at i and i + capacity), so the newest n samples are always one contiguous
// subarray and uPlot gets views, never copies.

export class Rings {
  readonly capacity: number;
  readonly names: string[];
  private readonly t: Float64Array;
  private readonly y: Float64Array[];
  private count = 0; // samples written in all
  /** Bumped with every append; plots redraw when it changed since their last frame. */
  version = 0;

  constructor(names: string[], capacity: number) {
    this.names = names;
    this.capacity = capacity;
    this.t = new Float64Array(2 * capacity);
    this.y = names.map(() => new Float64Array(2 * capacity));
  }

  /** A ring for `names` with the history `old` holds of them (NaN where it had none): a new
   * subscription keeps what was recorded of the signals that stay. */
  static carry(old: Rings, names: string[], capacity: number): Rings {
    const r = new Rings(names, capacity);
    const n = Math.min(old.size, capacity);
    if (!n) return r;
    const [t, ...cols] = old.window(Infinity, names);
    const from = t.length - n;
    const data = new Float64Array(names.length * n);
    cols.forEach((c, s) => data.set(c.subarray(from), s * n));
    r.append(t.subarray(from), data, n);
    return r;
  }

  get size(): number {
    return Math.min(this.count, this.capacity);
  }

  get lastTime(): number {
    return this.size ? this.t[this.end() - 1] : 0;
  }

  /** Append `n` samples: times, and `data` signal-major (signal i at data[i*n .. i*n+n)). */
  append(times: Float64Array, data: Float64Array, n: number): void {
    const c = this.capacity;
    for (let k = 0; k < n; k++) {
      const i = (this.count + k) % c;
      this.t[i] = this.t[i + c] = times[k];
      for (let s = 0; s < this.y.length; s++) {
        const v = data[s * n + k];
        this.y[s][i] = this.y[s][i + c] = v;
      }
    }
    this.count += n;
    this.version++;
  }

  private end(): number {
    return (this.count % this.capacity) + this.capacity; // one past the newest, in the upper copy
  }

  /** Views of the samples within `seconds` of the newest: [t, ...signals in `which`]. */
  window(seconds: number, which: string[]): Float64Array[] {
    const end = this.end();
    let lo = end - this.size;
    const t0 = this.lastTime - seconds;
    let hi = end;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (this.t[mid] < t0) lo = mid + 1;
      else hi = mid;
    }
    const cols = which.map((n) => {
      const s = this.names.indexOf(n);
      return s < 0 ? new Float64Array(end - lo).fill(NaN) : this.y[s].subarray(lo, end);
    });
    return [this.t.subarray(lo, end), ...cols];
  }

  /** The newest value of a signal (NaN when none). */
  latest(name: string): number {
    const s = this.names.indexOf(name);
    return s < 0 || !this.size ? NaN : this.y[s][this.end() - 1];
  }
}
