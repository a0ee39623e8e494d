// fetch with the service's refusal bodies turned into one error type, the CSRF token on every
// change, this tab's client id on every request, and a 401 reported as the end of the session.
// Every request of the HMI goes through here.
import type { Refusal, ValidationIssue } from "./types";

/** A request the service answered with 4xx/5xx, or could not be reached. */
export class ApiError extends Error {
  constructor(
    readonly status: number, // 0: no answer (connection lost)
    readonly refusal: Refusal,
  ) {
    super(refusal.message);
  }
}

/** Told whether each request reached the service (true) or failed on the network (false). */
export const reachListeners = new Set<(reached: boolean) => void>();
/** Told when the service answered 401: the session is gone (expired, logged out elsewhere). */
export const unauthorizedListeners = new Set<() => void>();

// as api/auth.py CSRF_COOKIE and CSRF_HEADER: the page echoes the cookie on every change
const CSRF_COOKIE = "inbetrieb_csrf";
const CSRF_HEADER = "X-CSRF-Token";

// as api/auth.py CLIENT_HEADER: control of a machine is held by one tab, not by a browser
const CLIENT_HEADER = "X-Inbetrieb-Client";

function newClientId(): string {
  const bytes = crypto.getRandomValues(new Uint8Array(12));
  return Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
}

/** This tab's id, new with every page load (a reload is a new tab as far as control goes; the
 * grace period keeps the machine for the reloaded page's "Take over here"). The websocket
 * sends it as its `client` query parameter. */
export const clientId = newClientId();

function csrfToken(): string | null {
  const pair = document.cookie.split("; ").find((c) => c.startsWith(`${CSRF_COOKIE}=`));
  return pair ? pair.slice(CSRF_COOKIE.length + 1) : null; // as set: the service compares it with the cookie
}

/** How a body is sent (JSON, or text as is with its type) and how the answer is read. */
interface Options {
  contentType?: string; // a text body's type; without it the body is sent as JSON
  binary?: boolean; // the answer is samples (ArrayBuffer), not JSON or text
}

async function request<T>(method: string, url: string, body?: unknown, opts: Options = {}): Promise<T> {
  const headers: Record<string, string> = { [CLIENT_HEADER]: clientId };
  if (body !== undefined) headers["content-type"] = opts.contentType ?? "application/json";
  const csrf = method === "GET" || method === "HEAD" ? null : csrfToken();
  if (csrf) headers[CSRF_HEADER] = csrf;
  let res: Response;
  try {
    res = await fetch(url, {
      method,
      headers,
      body: body === undefined ? undefined : body instanceof Blob ? body : opts.contentType ? String(body) : JSON.stringify(body),
    });
  } catch {
    reachListeners.forEach((f) => f(false));
    throw new ApiError(0, { message: "no connection to the service", problems: [] });
  }
  reachListeners.forEach((f) => f(true));
  if (res.status === 401) unauthorizedListeners.forEach((f) => f());
  const type = res.headers.get("content-type") ?? "";
  if (res.ok && opts.binary) return (await res.arrayBuffer()) as T;
  if (res.status === 204) return undefined as T; // no content, whatever the type says
  const payload: unknown = type.includes("json") ? await res.json() : await res.text();
  if (!res.ok) throw new ApiError(res.status, refusalOf(res.status, payload));
  return payload as T;
}

function refusalOf(status: number, payload: unknown): Refusal {
  const detail = (payload as { detail?: unknown } | null)?.detail;
  if (detail && typeof detail === "object" && !Array.isArray(detail)) {
    const r = detail as Partial<Refusal>;
    return { ...r, message: r.message ?? `HTTP ${status}`, problems: r.problems ?? [] };
  }
  if (Array.isArray(detail)) {
    // schema violations: the service words each one as a sentence (the field's meaning,
    // the rule, its unit), so no pydantic text ("Input should be …") reaches the operator
    const issues = detail as ValidationIssue[];
    return { message: issues.map((i) => i.text).join(" ") || "the request was refused as invalid", problems: [] };
  }
  return { message: typeof payload === "string" && payload ? payload : `HTTP ${status}`, problems: [] };
}

export const http = {
  get: <T>(url: string) => request<T>("GET", url),
  post: <T>(url: string, body: unknown) => request<T>("POST", url, body),
  /** A file's text as is: `text/plain` (parameter import) or e.g. `text/csv` (trace import). */
  postText: <T>(url: string, text: string, contentType = "text/plain") => request<T>("POST", url, text, { contentType }),
  /** A file as the body, as it is (a bundle's zip). */
  postFile: <T>(url: string, file: Blob, contentType: string) => request<T>("POST", url, file, { contentType }),
  put: <T>(url: string, body: unknown) => request<T>("PUT", url, body),
  patch: <T>(url: string, body: unknown) => request<T>("PATCH", url, body),
  del: <T>(url: string) => request<T>("DELETE", url),
  text: (url: string) => request<string>("GET", url),
  /** Samples (a binary frame, see `decodeFrame`). */
  bytes: (url: string) => request<ArrayBuffer>("GET", url, undefined, { binary: true }),
};
