"""Service settings: environment variables `INBETRIEB_*` or the `inbetrieb serve` options."""

from __future__ import annotations

import ipaddress
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, field_validator
from pydantic_settings import BaseSettings, NoDecode, SettingsConfigDict

from api.control import GRACE_S


class Settings(BaseSettings):
    model_config = SettingsConfigDict(env_prefix="INBETRIEB_")

    db_path: Path = Field(Path("var/inbetrieb.sqlite"), description="SQLite file")
    demo: bool = Field(True, description="create the demo lathe in a fresh store")
    loop_period_s: float = Field(
        0.002, gt=0, le=0.1, description="real-time loop period of each worker"
    )
    workers: int = Field(0, ge=0, le=256, description="worker processes (0: one per core)")
    cluster: str | None = Field(
        None,
        description="Ray cluster: the head's GCS address HOST:PORT (the gateway on a cluster "
        "node) or ray://HOST:PORT (Ray Client from anywhere else; the gateway's code is shipped "
        "to the actors): workers become Ray actors spread over the nodes",
    )
    frame_s: float = Field(0.02, gt=0, le=1, description="telemetry frame period")
    max_frame_samples: int = Field(1000, ge=10, description="decimate beyond this per frame")
    send_buffer_bytes: int = Field(
        131072, ge=16384, description="kernel send buffer per connection (slow-client detection)"
    )
    header_timeout_s: float = Field(
        10.0, gt=0, le=300, description="a request head not complete this long after it began: 408"
    )
    client_stall_s: float = Field(
        10.0, gt=0, description="a telemetry client whose send takes longer is disconnected"
    )
    trace_dir: Path | None = Field(
        None, description="trace library files and recordings (default: traces/ beside the db)"
    )
    recordings_quota_mb: float = Field(
        2048.0,
        gt=0,
        description="disk space all recordings together may take (MB); a recording stops "
        "when it is used up, and none starts",
    )
    library_quota_mb: float = Field(
        4096.0,
        gt=0,
        description="disk space the trace library may take (MB), its derived files (the "
        "Rerun .rrd of a trace) included: beyond, nothing more is stored (507)",
    )
    library_user_quota_mb: float = Field(
        1024.0, gt=0, description="of that, what one user's saved and imported traces may take"
    )
    history_days: float = Field(
        90.0,
        gt=0,
        le=36500,
        description="the machine log (job errors, events, power-ons, notes) keeps rows this "
        "many days; the audit trail (commands, parameters, control) keeps its own for ever",
    )
    history_rows: int = Field(
        200_000,
        ge=1000,
        le=100_000_000,
        description="... and at most this many rows per machine (about 200 bytes each on disk)",
    )
    flight_before_s: float = Field(
        8.0, gt=0, le=15, description="the flight recorder saves this much before a job error"
    )
    flight_after_s: float = Field(2.0, gt=0, le=5, description="... and this much after it")
    flight_minutes: float = Field(
        5.0,
        gt=0,
        le=60,
        description="the flight recorder's long tier holds the main signals this long, one "
        "sample in `flight_decimation` cycles: about 17 channels × 8 B per sample, 4.1 MB per "
        "machine at 5 min and 100 Hz",
    )
    flight_decimation: int = Field(10, ge=1, le=1000, description="... one sample in this many")
    flight_keep: int = Field(
        20, ge=1, le=10_000, description="the newest job-error traces kept per machine"
    )
    ws_ticket_s: float = Field(
        30.0, gt=0, le=300, description="a websocket ticket is good this long (once)"
    )
    frontend_dir: Path = Field(
        Path(__file__).resolve().parents[1] / "frontend" / "dist",
        description="built browser HMI served at / (make builds it)",
    )
    exercises_dir: Path = Field(
        Path(__file__).resolve().parents[1] / "exercises",
        description="the shipped training exercises (TOML files); an installed package, as "
        "in the container image, has them elsewhere than a source checkout",
    )
    chromium: Path = Field(
        Path("/usr/bin/chromium"), description="Chromium, to print the report as PDF"
    )
    host: str = Field("127.0.0.1", description="the address the service binds")
    port: int = Field(8000, ge=0, le=65535, description="its port")
    # a list from the environment as a container or a systemd unit sets it: comma-separated
    allowed_hosts: Annotated[list[str], NoDecode] = Field(
        default_factory=list,
        description="Host names clients reach the service by, besides loopback and `host` "
        "(INBETRIEB_ALLOWED_HOSTS=a.example,b.example)",
    )
    log_format: Literal["text", "json"] = Field(
        "text", description="the log on stderr: lines of text, or one JSON object per line"
    )
    log_level: Literal["debug", "info", "warning", "error"] = Field(
        "warning", description="info adds an access line per request (and websocket)"
    )
    tls_cert: Path | None = Field(None, description="TLS certificate (PEM): it serves HTTPS")
    tls_key: Path | None = Field(None, description="the certificate's private key (PEM)")
    behind_proxy: str | None = Field(
        None,
        description="served through the reverse proxy at this address (or these, comma-"
        "separated, or a network such as 10.42.0.0/16) that terminates TLS: only its "
        "X-Forwarded-For/-Proto headers count",
    )

    control_grace_s: float = Field(
        GRACE_S,
        gt=0,
        le=3600,
        description="a machine's control outlives its holder's last connection this long, s",
    )

    @field_validator("allowed_hosts", mode="before")
    @classmethod
    def _comma_separated(cls, v: object) -> object:
        return [h.strip() for h in v.split(",") if h.strip()] if isinstance(v, str) else v

    @field_validator("behind_proxy")
    @classmethod
    def _addresses(cls, v: str | None) -> str | None:
        if not v:  # an empty variable: no proxy
            return None
        # uvicorn would take a name or "*" too: trusting anyone's forwarded headers is refused
        for part in v.split(","):
            try:
                ipaddress.ip_network(part.strip(), strict=False)
            except ValueError:
                raise ValueError(
                    f"the proxy is an IP address or network (10.0.0.5, 10.42.0.0/16), not {part!r}"
                ) from None
        return v

    @property
    def https(self) -> bool:
        """It serves HTTPS itself (for the login link)."""
        return self.tls_cert is not None

    @property
    def traces_path(self) -> Path:
        return self.trace_dir or self.db_path.parent / "traces"
