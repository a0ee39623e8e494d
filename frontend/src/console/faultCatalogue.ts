// The fault catalogue as the service's OpenAPI schema describes it (api/faults.py): every
// kind with its title (the instructor's words) and sentence, its fields with type, range, default and unit (the field's
// description). The form is built from it, so a new fault kind needs no frontend change.
import { http } from "../api/http";

export interface FaultField {
  name: string;
  type: "number" | "integer" | "axis";
  description: string;
  min?: number;
  max?: number;
  exclusiveMin?: boolean;
  default?: number;
  required: boolean;
}

export interface FaultKind {
  kind: string;
  /** "Motor wired inverted": the model's title in the schema */
  title: string;
  description: string;
  fields: FaultField[];
}

interface JsonSchema {
  title?: string;
  properties?: Record<string, JsonSchema>;
  required?: string[];
  description?: string;
  type?: string;
  const?: string;
  minimum?: number;
  maximum?: number;
  exclusiveMinimum?: number;
  default?: number;
  oneOf?: { $ref: string }[];
}

let cached: Promise<FaultKind[]> | null = null;

/** The catalogue (read once per page). */
export function faultCatalogue(): Promise<FaultKind[]> {
  cached ??= http
    .get<{ components: { schemas: Record<string, JsonSchema> } }>("/openapi.json")
    .then((doc) => parse(doc.components.schemas))
    .catch((e: unknown) => {
      cached = null; // ask again next time
      throw e;
    });
  return cached;
}

function parse(schemas: Record<string, JsonSchema>): FaultKind[] {
  const refs = schemas.FaultInject?.properties?.fault?.oneOf ?? [];
  return refs.map(({ $ref }) => {
    const m = schemas[$ref.split("/").pop() ?? ""];
    const props = m.properties ?? {};
    const fields = Object.entries(props)
      .filter(([name]) => name !== "kind")
      .map(([name, p]): FaultField => ({
        name,
        type: name === "axis" ? "axis" : p.type === "integer" ? "integer" : "number",
        description: p.description ?? "",
        min: p.exclusiveMinimum ?? p.minimum,
        exclusiveMin: p.exclusiveMinimum !== undefined,
        max: p.maximum,
        default: p.default,
        required: (m.required ?? []).includes(name),
      }));
    const kind = props.kind?.const ?? "";
    return { kind, title: m.title ?? kind, description: m.description ?? "", fields };
  });
}

/** "0 < v ≤ 1000", "1 … 6": a field's range as the schema says it. */
export function rangeText(f: FaultField): string {
  if (f.min === undefined && f.max === undefined) return "";
  if (!f.exclusiveMin && f.min !== undefined && f.max !== undefined) return `${f.min} … ${f.max}`;
  const lo = f.min === undefined ? "" : `${f.min} ${f.exclusiveMin ? "<" : "≤"} `;
  const hi = f.max === undefined ? "" : ` ≤ ${f.max}`;
  return `${lo}${f.name}${hi}`;
}
