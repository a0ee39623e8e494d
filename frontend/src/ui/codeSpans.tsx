// A schema description's `code spans` as code, the rest as text (no other markdown there).
export function codeSpans(text: string) {
  return text.split(/`([^`]+)`/).map((part, i) => (i % 2 ? <code key={i}>{part}</code> : part));
}
