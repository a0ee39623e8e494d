// One input of an assistant: its label, the value with its unit, and the error as typed.
export function AssistField(props: {
  label: string;
  unit: string;
  testid: string;
  value: string;
  error: string | null; // why the value is refused, or null
  disabled: boolean;
  onInput: (text: string) => void;
  size?: number;
  placeholder?: string;
}) {
  return (
    <label class="assist-field">
      <span>{props.label}</span>
      <span class="row">
        <input data-testid={props.testid} size={props.size ?? 8} value={props.value} placeholder={props.placeholder}
          aria-invalid={props.error !== null} disabled={props.disabled} onInput={(e) => props.onInput((e.target as HTMLInputElement).value)} />
        <span>{props.unit}</span>
      </span>
      {props.error !== null ? (
        <span class="inline-error" data-testid={`${props.testid}-error`} role="alert">
          {props.error}
        </span>
      ) : null}
    </label>
  );
}
