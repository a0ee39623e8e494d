import { useEffect, useRef, useState } from "preact/hooks";
import type { AxisStatus } from "../api/types";

/** The gear a calculator works on: the axis' gear in use until the user picks one. A status
 * that comes and goes (a reconnect, a slow first status) must not undo the user's pick;
 * another axis starts again from its own gear in use. */
export function useGear(axis: AxisStatus | undefined): [number, (gear: number) => void] {
  const [gear, setGear] = useState(1);
  const pickedFor = useRef<string | null>(null); // the axis whose gear the user picked
  useEffect(() => {
    if (axis && pickedFor.current !== axis.name) {
      pickedFor.current = null;
      setGear(Math.max(1, axis.gear ?? 1));
    }
  }, [axis?.name]);
  const pick = (g: number) => {
    pickedFor.current = axis?.name ?? null;
    setGear(g);
  };
  return [gear, pick];
}
