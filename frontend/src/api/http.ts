// fetch with the service's refusal bodies turned into one error type.
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

async function request<T>(method: string, url: string, body?: unknown, text = false): Promise<T> {
  let res: Response;
  try {
    res = await fetch(url, {
      method,
      headers: body === undefined ? {} : { "content-type": text ? "text/plain" : "application/json" },
      body: body === undefined ? undefined : text ? String(body) : JSON.stringify(body),
    });
  } catch {
    reachListeners.forEach((f) => f(false));
    throw new ApiError(0, { message: "no connection to the service", problems: [] });
  }
  reachListeners.forEach((f) => f(true));
  const type = res.headers.get("content-type") ?? "";
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
  postText: <T>(url: string, text: string) => request<T>("POST", url, text, true),
  put: <T>(url: string, body: unknown) => request<T>("PUT", url, body),
  patch: <T>(url: string, body: unknown) => request<T>("PATCH", url, body),
  del: <T>(url: string) => request<T>("DELETE", url),
  text: (url: string) => request<string>("GET", url),
};
