// An assistant's form made from the JSON schema of its request (GET /api/assistants, from
// the descriptor in nc_sim/assist/registry.py): each input with its label, unit and range,
// checked as typed (the service checks again). A new assistant needs no frontend change.
import type { AxisStatus } from "../api/types";
import { checkNumber } from "./CalcParts";

interface JsonSchema {
  type?: string;
  description?: string;
  title?: string;
  minimum?: number;
  maximum?: number;
  exclusiveMinimum?: number;
  default?: unknown;
  enum?: number[];
  anyOf?: JsonSchema[];
  items?: JsonSchema;
  minItems?: number;
  maxItems?: number;
  properties?: Record<string, JsonSchema>;
  required?: string[];
  $ref?: string;
  $defs?: Record<string, JsonSchema>;
  "x-unit"?: string;
  "x-labels"?: Record<string, string>;
  "x-title"?: string;
  "x-axis-kinds"?: string[];
}

type Kind = "number" | "integer" | "choice" | "flag" | "axis" | "numbers" | "rows";

export interface FormField {
  name: string;
  label: string;
  kind: Kind;
  unit: string;
  min?: number;
  max?: number;
  exclusiveMin: boolean;
  options: { value: number; label: string }[];
  nullable: boolean;
  required: boolean;
  start: string; // the default as text ("" for none)
  axisKinds: string[];
  columns: string[]; // of a table's rows
}

/** The fields of a request schema, in its order. */
export function formFields(schema: Record<string, unknown>): FormField[] {
  const s = schema as JsonSchema;
  const defs = s.$defs ?? {};
  return Object.entries(s.properties ?? {}).map(([name, p]) => {
    const nonNull = p.anyOf?.find((x) => x.type !== "null") ?? p;
    const nullable = !!p.anyOf?.some((x) => x.type === "null");
    const items = nonNull.items ?? {};
    const row = items.$ref ? defs[items.$ref.split("/").pop() ?? ""] : undefined;
    const kind: Kind = p["x-axis-kinds"]
      ? "axis"
      : nonNull.enum
        ? "choice"
        : nonNull.type === "boolean"
          ? "flag"
          : nonNull.type === "array"
            ? row
              ? "rows"
              : "numbers"
            : nonNull.type === "integer"
              ? "integer"
              : "number";
    const bounded = kind === "numbers" ? items : nonNull;
    const labels = p["x-labels"] ?? {};
    return {
      name,
      label: p["x-title"] ?? p.description ?? nonNull.description ?? name,
      kind,
      unit: bounded["x-unit"] ?? p["x-unit"] ?? "",
      min: bounded.exclusiveMinimum ?? bounded.minimum,
      max: bounded.maximum,
      exclusiveMin: bounded.exclusiveMinimum !== undefined,
      options: (nonNull.enum ?? []).map((v) => ({ value: v, label: labels[String(v)] ?? String(v) })),
      nullable,
      required: (s.required ?? []).includes(name),
      start: p.default === undefined || p.default === null ? "" : String(p.default),
      axisKinds: p["x-axis-kinds"] ?? [],
      columns: Object.keys(row?.properties ?? {}),
    };
  });
}

/** The texts a form starts with: every field's default. */
export const startTexts = (fields: FormField[]): Record<string, string> =>
  Object.fromEntries(fields.map((f) => [f.name, f.start]));

function numberOf(f: FormField, text: string): number | string {
  return checkNumber(text, f.name, f.min ?? -Infinity, f.max ?? Infinity, f.unit, f.exclusiveMin, f.kind === "integer");
}

/** The request body from the texts typed, and why a field is refused (by field name). */
export function formBody(fields: FormField[], texts: Record<string, string>, axis: string) {
  const body: Record<string, unknown> = {};
  const errors: Record<string, string> = {};
  for (const f of fields) {
    const text = (texts[f.name] ?? "").trim();
    if (f.kind === "axis") body[f.name] = axis;
    else if (f.kind === "flag") body[f.name] = text === "true";
    else if (text === "") {
      if (f.nullable) body[f.name] = null;
      else if (f.required) errors[f.name] = `${f.name}: a value is needed`;
    } else if (f.kind === "choice") body[f.name] = Number(text);
    else if (f.kind === "numbers" || f.kind === "rows") {
      const parts = text.split(",").filter((x) => x.trim());
      const checked = parts.map((x) => (f.kind === "rows" ? x.split(":") : [x]).map((v) => numberOf(f, v)));
      const bad = checked.flat().find((v): v is string => typeof v === "string");
      if (bad) errors[f.name] = bad;
      else if (f.kind === "rows" && checked.some((r) => r.length !== f.columns.length))
        errors[f.name] = `${f.name}: rows of ${f.columns.join(":")}`;
      else
        body[f.name] =
          f.kind === "rows" ? checked.map((r) => Object.fromEntries(f.columns.map((c, i) => [c, r[i]]))) : checked.map((r) => r[0]);
    } else {
      const v = numberOf(f, text);
      if (typeof v === "string") errors[f.name] = v;
      else body[f.name] = v;
    }
  }
  return { body, errors };
}

/** The machine's axes a field of kind "axis" offers. */
export const axesFor = (fields: FormField[], axes: AxisStatus[]): AxisStatus[] => {
  const kinds = fields.find((f) => f.kind === "axis")?.axisKinds ?? [];
  return kinds.length ? axes.filter((a) => kinds.includes(a.kind)) : axes;
};

/** The inputs of the form (the axis is chosen beside it). */
export function SchemaFields(props: {
  fields: FormField[];
  texts: Record<string, string>;
  errors: Record<string, string>;
  set: (name: string, text: string) => void;
  disabled: boolean;
  testid: string;
}) {
  const { fields, texts, errors, set, disabled, testid } = props;
  return (
    <>
      {fields.map((f) => {
        const id = `${testid}-${f.name}`;
        const value = texts[f.name] ?? "";
        if (f.kind === "axis") return null;
        if (f.kind === "flag")
          return (
            <label key={f.name} class="assist-field">
              <span>{f.label}</span>
              <input type="checkbox" data-testid={id} checked={value === "true"} disabled={disabled}
                onChange={(e) => set(f.name, String((e.target as HTMLInputElement).checked))} />
            </label>
          );
        if (f.kind === "choice")
          return (
            <label key={f.name} class="assist-field">
              <span>{f.label}</span>
              <select data-testid={id} value={value} disabled={disabled} onChange={(e) => set(f.name, (e.target as HTMLSelectElement).value)}>
                {f.nullable ? <option value="">(default)</option> : null}
                {f.options.map((o) => (
                  <option key={o.value} value={String(o.value)}>
                    {o.label}
                  </option>
                ))}
              </select>
            </label>
          );
        const hint = f.kind === "rows" ? f.columns.join(":") + ", …" : f.kind === "numbers" ? "a, b, …" : f.nullable ? "default" : "";
        return (
          <label key={f.name} class="assist-field">
            <span>{f.label}</span>
            <span class="row">
              <input data-testid={id} size={f.kind === "rows" || f.kind === "numbers" ? 24 : 8} value={value} placeholder={hint}
                aria-invalid={f.name in errors} disabled={disabled} onInput={(e) => set(f.name, (e.target as HTMLInputElement).value)} />
              <span>{f.unit}</span>
            </span>
            {f.name in errors ? (
              <span class="inline-error" data-testid={`${id}-error`} role="alert">
                {errors[f.name]}
              </span>
            ) : null}
          </label>
        );
      })}
    </>
  );
}
