"""Diagnostic bundles: a machine's lists, versions, diff, history and alarm traces in one zip,
and such a zip opened read-only as an offline machine."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field

from api.scope import TraceInfo
from api.versions import VersionDiff, VersionInfo


class BundleManifest(BaseModel):
    """What a bundle is and holds (its `manifest.json`)."""

    format: str = Field(description="'inbetrieb-bundle'")
    format_version: int = Field(ge=1)
    service_version: str = Field(description="of the service that made it")
    created_unix: float
    created_by: str
    machine_id: str
    machine_name: str
    history_entries: int = Field(ge=0)
    traces: list[str] = Field(description="the flight recorder's traces it carries (ids there)")
    lists: list[str] = Field(description="its parameter lists' file names")


class BundleInfo(BaseModel):
    """A bundle opened on this service: an offline machine."""

    id: str
    opened_unix: float
    opened_by: str
    manifest: BundleManifest
    traces: list[str] = Field(description="its traces in this service's library (ids here)")


class BundleDetail(BundleInfo):
    """The offline machine: what the bundle says about it."""

    machine: dict[str, Any] = Field(description="id, name, source")
    status: dict[str, Any] = Field(
        description="the machine's status, its flight recorder's and the service's, then"
    )
    versions: list[VersionInfo]
    diff: VersionDiff | None = Field(description="the live lists against the baseline, then")
    trace_infos: list[TraceInfo] = Field(description="its alarm traces in this library")
