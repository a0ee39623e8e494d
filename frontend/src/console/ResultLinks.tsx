// A class's results to take away, running or ended: CSV for a spreadsheet, the grade list
// to print.
export function ResultLinks(props: { cid: string }) {
  const base = `/api/classes/${encodeURIComponent(props.cid)}`;
  return (
    <span class="result-links">
      <a class="button secondary" href={`${base}/results.csv`} download data-testid="results-csv">Results (CSV)</a>{" "}
      <a class="button secondary" href={`${base}/results.pdf`} download data-testid="results-pdf">Grade list (PDF)</a>
    </span>
  );
}
