"""Parameter versions in the browser: set the baseline when nudged, take a version, change a
value, compare, roll back (confirmed) and Keep; screenshots at 1920×1080 and 1024×768."""

from __future__ import annotations

from playwright.sync_api import Page, expect

from tests.backend.server import Server
from tests.e2e.browser import panel, shot

KV_RAW = 2000  # getriebe[0].kv of the demo's X, 0.01/s: 20 1/s


def kv(srv: Server, mid: str) -> float:
    rows = srv.http.get(f"/api/machines/{mid}/parameters?scope=axis&target=X").json()
    return float(next(p["value"] for p in rows if p["name"] == "getriebe[0].kv"))


def test_take_change_compare_roll_back_keep(page: Page, srv: Server, mid: str) -> None:
    page.get_by_test_id("tab-Parameters").click()
    expect(page.get_by_test_id("baseline-nudge")).to_be_visible()  # nudged on the list too
    page.get_by_test_id("param-view-versions").click()
    box = panel(page, "versions")
    shot(page, "versions-nudge-desktop")
    box.get_by_test_id("baseline-now").click()
    expect(box.get_by_test_id("baseline-tag")).to_have_count(1)
    expect(box.get_by_test_id("baseline-nudge")).to_have_count(0)

    box.get_by_test_id("version-name").fill("kv 20")
    box.get_by_test_id("version-note").fill("before tuning X")
    box.get_by_test_id("version-take").click()
    row = box.get_by_test_id("version-row-kv 20")
    expect(row).to_contain_text("before tuning X")

    # a change through the list editor, kept
    page.get_by_test_id("param-view-list").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("P-AXIS-00099")
    params.get_by_test_id("param-input-getriebe[0].kv").fill("2500")
    params.get_by_test_id("param-apply").click()
    bar = page.get_by_test_id("trial-bar")
    bar.get_by_test_id("param-keep").click()
    assert kv(srv, mid) == 2500

    page.get_by_test_id("param-view-versions").click()
    box.get_by_test_id("version-row-kv 20").get_by_test_id("version-compare").click()
    expect(box.get_by_test_id("diff-summary")).to_contain_text(
        "version 'kv 20' → live parameters: 1"
    )
    diff = box.get_by_test_id("diff-row-X-getriebe[0].kv")
    expect(diff.get_by_test_id("diff-before")).to_have_text(str(KV_RAW))
    expect(diff.get_by_test_id("diff-after")).to_have_text("2500")
    expect(diff).to_contain_text("0.01/s")
    # engineering form as on the parameter page: 2000 × 0.01/s = 20 1/s, 2500 → 25 1/s
    expect(diff.get_by_test_id("diff-eng")).to_have_text("20\u00a01/s → 25\u00a01/s")
    shot(page, "versions-compare-desktop")

    box.get_by_test_id("version-row-kv 20").get_by_test_id("version-rollback").click()
    confirm = box.get_by_test_id("rollback-confirm")
    expect(confirm).to_contain_text("Roll back to kv 20? 1 value(s)")
    back = confirm.get_by_test_id("diff-row-X-getriebe[0].kv")
    expect(back.get_by_test_id("diff-before")).to_have_text("2500")
    expect(back.get_by_test_id("diff-after")).to_have_text(str(KV_RAW))
    assert kv(srv, mid) == 2500  # nothing written before the confirmation
    shot(page, "versions-rollback-confirm-desktop")
    confirm.get_by_test_id("rollback-do").click()
    expect(bar.get_by_test_id("param-trial")).to_contain_text("rollback to 'kv 20'")
    expect(bar.get_by_test_id("param-trial")).to_contain_text("X: getriebe[0].kv 2500 → 2000")
    assert kv(srv, mid) == KV_RAW
    expect(box.get_by_test_id("diff-summary")).to_contain_text("live parameters: 0 differences")

    page.set_viewport_size({"width": 1024, "height": 768})
    page.wait_for_timeout(300)
    overflow = page.evaluate("document.documentElement.scrollWidth - window.innerWidth")
    assert overflow <= 0, f"the versions view is {overflow} px too wide at 1024×768"
    shot(page, "versions-trial-tablet")
    box.get_by_test_id("diff-from").select_option("defaults")
    expect(box.get_by_test_id("diff-summary")).to_contain_text("the manuals' defaults → live")
    box.get_by_test_id("diff-summary").scroll_into_view_if_needed()
    shot(page, "versions-defaults-tablet")
    bar.get_by_test_id("param-keep").click()
    expect(bar.get_by_test_id("param-trial")).to_be_hidden()
    expect(bar.get_by_test_id("trial-message")).to_contain_text("✓ Kept")
    assert kv(srv, mid) == KV_RAW
    page.set_viewport_size({"width": 1920, "height": 1080})

    rows = srv.http.get(f"/api/machines/{mid}/audit", params={"kind": "version"}).json()["rows"]
    took_baseline, took, rolled_back = [r["action"] for r in reversed(rows)]  # oldest first
    assert took_baseline.startswith("took baseline 'baseline ")
    assert took.startswith("took version 'kv 20' (")
    assert rolled_back == "rolled back to version 'kv 20' (1 value changed)"
