// Who is logged in. The session is an HttpOnly cookie the page never sees; `me` is what the
// service says about it. Any 401 ends it here, wherever it came from.
import { computed, signal } from "@preact/signals";
import { ApiError, http, unauthorizedListeners } from "../api/http";
import type { LoginRequest, Me } from "../api/types";

const RETRY_MS = 1000;

/** The logged-in user; null: nobody (the login screen shows); undefined: not known yet. */
export const me = signal<Me | null | undefined>(undefined);
/** Someone is logged in: the machines, their socket and any polling run only then. */
export const loggedIn = computed(() => !!me.value);

/** This page watched through a share link that has ended (expired or revoked). */
export const shareEnded = signal(false);
unauthorizedListeners.add(() => {
  if (me.value?.guest) shareEnded.value = true;
  me.value = null;
});

/** Ask the service who the session belongs to. At start, until it answers; later (the
 * telemetry socket was refused) once, as the socket asks again when it reconnects. */
export async function loadMe(): Promise<void> {
  try {
    me.value = await http.get<Me>("/api/auth/me");
  } catch (e) {
    if (e instanceof ApiError && e.status === 401) return; // the listener set `me` to null
    if (me.value === undefined) setTimeout(() => void loadMe(), RETRY_MS); // service starting
  }
}

/** Log in; rejects with the refusal (ApiError: 401 wrong name or password, 429 too many tries). */
export async function login(name: string, password: string): Promise<void> {
  const body: LoginRequest = { name, password };
  me.value = await http.post<Me>("/api/auth/login", body);
}

/** End the session on the service (it clears the cookies); rejects (still logged in) when the
 * service could not be told, so nobody walks away from a session that still works. */
export async function logout(): Promise<void> {
  try {
    await http.post<null>("/api/auth/logout", {});
  } catch (e) {
    if (!(e instanceof ApiError && e.status === 401)) throw e; // 401: it had ended already
  }
  me.value = null;
}
