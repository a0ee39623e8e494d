// The seats' login links on paper: a card per seat (student, seat, class, a QR code of the
// link and the link itself, until when it works), printed with the browser's print dialog.
// Only the sheet prints (console.css @media print); on screen it stays hidden.
import { exercises } from "../state/classes";
import qrcode from "qrcode-generator";
import type { ClassInfo, SeatLink } from "../api/types";

/** A QR code of `text` as one SVG path (one square per dark module), error correction M. */
export function QrCode(props: { text: string; size_mm: number }) {
  const qr = qrcode(0, "M");
  qr.addData(props.text);
  qr.make();
  const n = qr.getModuleCount();
  let d = "";
  for (let r = 0; r < n; r++) for (let c = 0; c < n; c++) if (qr.isDark(r, c)) d += `M${c} ${r}h1v1h-1z`;
  const q = 4; // the quiet zone the standard asks for, in modules
  return (
    <svg class="qr" viewBox={`${-q} ${-q} ${n + 2 * q} ${n + 2 * q}`} width={`${props.size_mm}mm`} height={`${props.size_mm}mm`}
      role="img" aria-label="QR code of the login link" shape-rendering="crispEdges">
      <rect x={-q} y={-q} width={n + 2 * q} height={n + 2 * q} fill="#fff" />
      <path d={d} fill="#000" />
    </svg>
  );
}

export function LinkSheet(props: { info: ClassInfo; links: SeatLink[] }) {
  const { info, links } = props;
  const plan = info.exercises.map((id) => exercises.value.find((e) => e.id === id)?.title ?? id).join(" → ");
  return (
    <div class="print-sheet" data-testid="link-sheet" aria-hidden="true">
      {links.map((l) => {
        const seat = info.seats.find((s) => s.n === l.n);
        return (
          <section class="link-card" key={l.n} data-testid={`link-card-${l.n}`}>
            <h2>{seat?.student || `Seat ${l.n}`}</h2>
            <p>
              Seat {l.n} · class <b>{info.title || info.id}</b>{plan !== info.title ? ` · ${plan}` : ""}
            </p>
            <QrCode text={l.url} size_mm={45} />
            <p class="mono link-text">{l.url}</p>
            <p class="hint">
              Scan or type the link once; it works until {new Date(l.expires_unix * 1000).toLocaleString()}. Lost it? Ask your
              instructor for a new one.
            </p>
          </section>
        );
      })}
    </div>
  );
}
