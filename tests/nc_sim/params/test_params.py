"""Parameter registry and the native list format."""

from __future__ import annotations

from pathlib import Path

import pytest

from nc_sim.config import apply_overrides, demo_machine
from nc_sim.params import ParamError, ParamListError, Scope, format_list, parse_list, registry
from nc_sim.params.listfile import parse_value
from nc_sim.units import AxisKind, Quantity, raw_unit, to_eng, v_reso_digits_per_unit_s

DATA = Path(__file__).parent / "data"
KV = registry().by_id("P-AXIS-00099")  # getriebe[i].kv, UNS32
B1 = registry().by_id("P-AXIS-00026")  # getriebe[i].beschl_kennlinie.b1, REAL64
DOMAIN_IDS = [
    "P-AXIS-00001",
    "P-AXIS-00078",
    "P-AXIS-00079",
    "P-AXIS-00109",
    "P-AXIS-00202",
    "P-AXIS-00212",
    "P-AXIS-00216",
    "P-AXIS-00217",
    "P-AXIS-00220",
    "P-AXIS-00224",
    "P-AXIS-00320",
    "P-AXIS-00455",
    "P-AXIS-00767",
    "P-CHAN-00052",
    "P-CHAN-00056",
    "P-CHAN-00058",
    "P-CHAN-00071",
    "P-CHAN-00097",
    "P-TOOL-00013",
]


@pytest.mark.parametrize("pid", DOMAIN_IDS)
def test_every_parameter_domain_names_is_registered(pid: str) -> None:
    d = registry().by_id(pid)
    assert d.name and d.title


def test_manual_defaults_and_units() -> None:
    r = registry()
    kv = r.by_id("P-AXIS-00099")
    assert (kv.name, kv.default, kv.per_gear) == ("getriebe[i].kv", 1000, True)
    assert to_eng(kv.quantity, 1000) == pytest.approx(10.0)  # kv 1000 = 10/s [DOMAIN §2]
    vb = r.by_id("P-AXIS-00212")
    # 10000 rpm = 60000000 in 0.001 °/s [002 P-AXIS-00212]
    assert to_eng(vb.quantity, 60_000_000) / 6.0 == pytest.approx(10000.0)
    assert (vb.default, vb.hi) == (200000, 2000000000)  # [002 p.53-54]
    assert raw_unit(Quantity.VELOCITY, AxisKind.LINEAR) == "µm/s"
    assert r.by_id("P-AXIS-00233").effect.value == "restart"  # [004 §3.4]


@pytest.mark.parametrize(
    ("name", "scope"),
    [("spindle_channel_excerpt.lis", Scope.CHANNEL), ("axis_excerpt.lis", Scope.AXIS)],
)
def test_manual_excerpts_round_trip(name: str, scope: Scope) -> None:
    text = (DATA / name).read_text(encoding="utf-8")
    plist = parse_list(text, scope)
    assert plist.text() == text  # lossless, comments and layout kept
    again = parse_list(format_list(plist.values, scope), scope)
    assert again.values == plist.values  # canonical writer keeps every value


def test_values_are_typed() -> None:
    plist = parse_list((DATA / "spindle_channel_excerpt.lis").read_text(), Scope.CHANNEL)
    v = plist.values
    assert v["spindel[0].m3_synch"] == 0x00020002  # PLC_INFO | MVS_SVS [000 P-CHAN-00045]
    assert v["spindel[0].m4_synch"] == 0x00020004
    assert v["spindel[0].m5_synch"] == 0x00020002  # hex form accepted
    assert v["spindel[1].bezeichnung"] == "S2"
    assert v["spindel[0].range_table[2].max_speed"] == 3360
    axis = parse_list((DATA / "axis_excerpt.lis").read_text(), Scope.AXIS).values
    assert axis["getriebe[0].beschl_kennlinie.b3"] == pytest.approx(-1.92901234e-10)
    assert axis["kenngr.achs_typ"] == 4


def test_bad_lines_are_rejected_with_line_numbers() -> None:
    text = (
        "getriebe[0].kv 1000\ngetriebe[1].kv 0\nfoo.bar 1\ngetriebe[7].kv 100\n"
        "getriebe[0].slope_profil.a_beschl 5000\nkenngr.achs_typ ACHSTYP_BOGUS\n"
    )
    with pytest.raises(ParamListError) as exc:
        parse_list(text, Scope.AXIS)
    lines = {e.line: str(e) for e in exc.value.errors}
    assert set(lines) == {2, 3, 4, 5, 6}
    assert "range 1 … 4294967295 0.01/s" in lines[2] and "P-AXIS-00099" in lines[2]
    assert "unknown axis parameter 'foo.bar'" in lines[3]
    assert "index 7" in lines[4]
    # a_beschl is capped by a_max (default 1000 mm/s²) [002 P-AXIS-00001]
    assert "1 … 1000 mm/s²" in lines[5] and "P-AXIS-00008" in lines[5]


def test_rejected_overrides_change_nothing() -> None:
    cfg = demo_machine()
    before = dict(cfg.axis("X").values)
    with pytest.raises(ParamListError):
        apply_overrides(
            cfg, Scope.AXIS, "X", {"getriebe[0].kv": 3000, "getriebe[0].dynamik.a_max": 0}
        )
    assert cfg.axis("X").values == before


@pytest.mark.parametrize(
    "text",
    ["２０００", "2_000", "0x_10", "1_0.5", "１e3", "٣", "0x１０", "1e", "--5", " ", "nan", "inf"],
)
def test_numbers_are_ascii_decimal_or_hex_only(text: str) -> None:
    # Python's int() and float() take full-width and Arabic-Indic digits and underscores; the
    # controller's list format does not, so a value typed on another keyboard is refused
    with pytest.raises(ParamError, match=r"not a (finite )?number|value missing"):
        parse_value(KV, "getriebe[0].kv", text)
    with pytest.raises(ParamError):
        parse_value(B1, "getriebe[0].beschl_kennlinie.b1", text)


def test_integers_hex_and_reals_still_parse() -> None:
    assert parse_value(KV, "getriebe[0].kv", "2000") == 2000
    assert parse_value(KV, "getriebe[0].kv", "0x7D0") == 2000
    assert parse_value(KV, "getriebe[0].kv", "+0002000") == 2000
    assert parse_value(B1, "getriebe[0].beschl_kennlinie.b1", "-1.92901234E-10") == -1.92901234e-10
    assert parse_value(B1, "getriebe[0].beschl_kennlinie.b1", ".5") == 0.5


@pytest.mark.parametrize("text", ["9" * 400, "0x" + "F" * 300, "-" + "9" * 400, "4294967296"])
def test_huge_integers_are_out_of_the_types_range(text: str) -> None:
    # kv is UNS32 [004 P-AXIS-00099], whatever the number of digits; the message names the
    # parameter's own range 1 … 4294967295, not the type's 0 … 4294967295
    with pytest.raises(ParamError, match=r"out of range 1 … 4294967295 0\.01/s") as exc:
        parse_value(KV, "getriebe[0].kv", text)
    assert exc.value.limits is not None and exc.value.limits[:2] == (1, 4294967295)
    assert len(str(exc.value)) < 200


def test_a_huge_integer_for_a_real_is_refused_not_an_overflow() -> None:
    with pytest.raises(ParamError, match="out of range"):
        parse_value(B1, "getriebe[0].beschl_kennlinie.b1", "9" * 400)
    with pytest.raises(ParamError, match="not a finite number"):
        parse_value(B1, "getriebe[0].beschl_kennlinie.b1", "1e400")


def test_flag_values_take_the_same_numbers() -> None:
    m3 = registry().by_id("P-CHAN-00045")
    name = "spindel[0].m3_synch"
    assert parse_value(m3, name, "PLC_INFO | 0x00000002") == 0x00020002
    with pytest.raises(ParamError):
        parse_value(m3, name, "PLC_INFO | ２")
    with pytest.raises(ParamError, match="out of range"):
        parse_value(m3, name, "0x" + "F" * 300)


def test_a_name_twice_in_one_list_is_refused_naming_both_lines() -> None:
    text = "getriebe[0].kv 1000\n# comment\ngetriebe[0].kv 2000\n"
    with pytest.raises(ParamListError) as exc:
        parse_list(text, Scope.AXIS)
    (err,) = exc.value.errors
    assert err.line == 3 and "already set in line 1" in str(err)


def test_speed_scaling_reproduces_the_manuals_examples() -> None:
    """[000 §2.2.4.1] 32767 increments for 3000 rpm per minute -> 32767/1080000000;
    [§2.2.4.2] 1 increment for 1 rpm -> 1/360000."""
    per_deg_s = v_reso_digits_per_unit_s(32767, 1080000000, 0, 0.001)
    assert 3000 * 6.0 * per_deg_s == pytest.approx(32767.0)
    assert 1 * 6.0 * v_reso_digits_per_unit_s(1, 360000, 0, 0.001) == pytest.approx(1.0)
    # per second and per sampling interval: the same output for 1/60 and 1/60000 of the path
    assert v_reso_digits_per_unit_s(32767, 1080000000 / 60, 1, 0.001) == pytest.approx(per_deg_s)
    per_cycle = v_reso_digits_per_unit_s(32767, 1080000000 / 60000, 2, 0.001)
    assert per_cycle == pytest.approx(per_deg_s)


def test_open_position_loop_mode_and_the_old_changeover_names_are_accepted() -> None:
    """P-AXIS-00320 OPEN_POSITION_LOOP_MODE [000 §2.2.4.1]; P-AXIS-00265/00266, replaced by
    00767/00768 but keeping their function [001 p.18-19]."""
    text = (
        "antr.operation_mode OPEN_POSITION_LOOP_MODE\n"
        "antr.v_time_base 0\n"
        "antr.v_reso_num 32767\n"
        "antr.v_reso_denom 1080000000\n"
        "antr.velocity_position_control_on 1200000\n"
        "antr.velocity_position_control_off 600000\n"
    )
    values = parse_list(text, Scope.AXIS).values
    assert values["antr.operation_mode"] == 3
    assert values["antr.velocity_position_control_on"] == 1200000
    assert registry().by_id("P-AXIS-00265").name == "antr.velocity_position_control_on"
    assert registry().by_id("P-AXIS-00266").name == "antr.velocity_position_control_off"
