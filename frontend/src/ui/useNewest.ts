import { useRef, useState } from "preact/hooks";

/** A value the panel loads from the service, again after each change it makes (and on a
 * timer): only the newest load's answer is shown, so a slower answer to an earlier load (the
 * list fetched as the panel opened, arriving after the one fetched after a create) never
 * replaces it. Returns the value and `show(load)`, which waits for that load. */
export function useNewest<T>(initial: T): [T, (load: Promise<T>) => Promise<void>] {
  const [value, setValue] = useState<T>(initial);
  const newest = useRef(0);
  const show = async (load: Promise<T>) => {
    const n = ++newest.current;
    const v = await load;
    if (n === newest.current) setValue(v);
  };
  return [value, show];
}
