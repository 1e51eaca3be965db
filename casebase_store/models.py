"""SQLAlchemy 2.0 typed models of the case base store.

Tables: ``schema_version`` (one row), ``case_bases`` (configuration, the fitted model, an
identity that changes when a case base is replaced and a version that grows with every change
to its cases), ``cases``, ``case_representations`` (per-case cached representations such as path
signatures and DTW envelopes) and ``maintenance_log`` (every trim, retain, revise and edit, with
novelty, benefit and reason). Arrays are stored as ``.npy`` bytes.

Case ids are never reused (``AUTOINCREMENT`` on SQLite; sequences on PostgreSQL): a process
holding the id of a case that was deleted can never write into a case that took its place.
"""

from __future__ import annotations

from datetime import UTC, datetime

from sqlalchemy import (
    DateTime,
    Float,
    ForeignKey,
    Index,
    Integer,
    LargeBinary,
    String,
    Text,
    UniqueConstraint,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship

#: Bump when the tables change; a store written with another version is refused clearly
#: (version 1 stores are converted by ``upgrade_store``).
SCHEMA_VERSION = 2
#: the schema versions `posecbr casebase upgrade` converts from
UPGRADABLE = (1,)


def utcnow() -> datetime:
    return datetime.now(UTC)


class Base(DeclarativeBase):
    pass


class SchemaVersion(Base):
    __tablename__ = "posecbr_schema_version"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    version: Mapped[int] = mapped_column(Integer)


class CaseBaseRow(Base):
    """A named case base: its feature configuration (JSON + hash), similarity measure and fitted
    model; ``uid`` names this case base for ever (a replaced one gets a new uid), ``version``
    grows by one with every committed change to its cases."""

    __tablename__ = "case_bases"
    __table_args__ = {"sqlite_autoincrement": True}

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    uid: Mapped[str] = mapped_column(String(32), unique=True)
    version: Mapped[int] = mapped_column(Integer, default=1)
    name: Mapped[str] = mapped_column(String(200), unique=True)
    feature_config: Mapped[str] = mapped_column(Text)  # canonical JSON
    feature_hash: Mapped[str] = mapped_column(String(64), index=True)
    feature_names: Mapped[str] = mapped_column(Text)  # JSON list of machine names
    feature_words: Mapped[str] = mapped_column(Text)  # JSON list of human words
    similarity_config: Mapped[str] = mapped_column(Text)  # JSON {"name": ..., params...}
    model: Mapped[str] = mapped_column(Text, default="{}")  # JSON: what fit learned, k, ...
    code_version: Mapped[str] = mapped_column(String(40))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)

    cases: Mapped[list[CaseRow]] = relationship(
        back_populates="case_base", cascade="all, delete-orphan", passive_deletes=True
    )


class CaseRow(Base):
    """One case: problem (features) + solution (label) + provenance."""

    __tablename__ = "cases"
    # the cases of a source, found without reading every case (train --append looks for the
    # clips it adds among them); a store made before it has none until `casebase upgrade`
    __table_args__ = (
        Index("ix_cases_case_base_id_source", "case_base_id", "source"),
        {"sqlite_autoincrement": True},
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    case_base_id: Mapped[int] = mapped_column(
        ForeignKey("case_bases.id", ondelete="CASCADE"), index=True
    )
    label: Mapped[str] = mapped_column(Text)
    features: Mapped[bytes] = mapped_column(LargeBinary)  # .npy bytes
    source: Mapped[str] = mapped_column(Text, default="")
    frame_start: Mapped[int | None] = mapped_column(Integer, nullable=True)
    frame_end: Mapped[int | None] = mapped_column(Integer, nullable=True)
    subject: Mapped[str | None] = mapped_column(Text, nullable=True)
    skeleton: Mapped[str | None] = mapped_column(String(64), nullable=True)
    origin: Mapped[str] = mapped_column(String(16), default="trained")  # trained|retained|revised
    # a SHA-256 of the poses of the clip the case was made of (its mirror image's case too):
    # what tells a copy of that clip under another file name (train --append). NULL when not
    # known: a case stored before it was kept, or not made from a clip of train. A store made
    # before has no such column until `casebase upgrade` adds it (read and written as it is);
    # deferred: what reads a whole case does not name it
    poses: Mapped[str | None] = mapped_column(String(64), nullable=True, deferred=True)
    active: Mapped[bool] = mapped_column(default=True)  # False once trimmed (kept for history)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
    updated_at: Mapped[datetime] = mapped_column(
        DateTime(timezone=True), default=utcnow, onupdate=utcnow
    )

    case_base: Mapped[CaseBaseRow] = relationship(back_populates="cases")


class RepresentationRow(Base):
    """A cached per-case representation, e.g. ``signature:depth=2,time=1`` or a DTW envelope."""

    __tablename__ = "case_representations"
    __table_args__ = (UniqueConstraint("case_id", "kind"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    case_id: Mapped[int] = mapped_column(ForeignKey("cases.id", ondelete="CASCADE"), index=True)
    kind: Mapped[str] = mapped_column(String(200))
    data: Mapped[bytes] = mapped_column(LargeBinary)


class MaintenanceRow(Base):
    """One maintenance step: ``trim``, ``retain``, ``revise``, ``edit`` (CNN/RENN/ICF), ..."""

    __tablename__ = "maintenance_log"
    __table_args__ = {"sqlite_autoincrement": True}

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    case_base_id: Mapped[int] = mapped_column(
        ForeignKey("case_bases.id", ondelete="CASCADE"), index=True
    )
    case_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    action: Mapped[str] = mapped_column(String(16))
    novelty: Mapped[float | None] = mapped_column(Float, nullable=True)
    benefit: Mapped[float | None] = mapped_column(Float, nullable=True)
    reason: Mapped[str] = mapped_column(Text, default="")
    at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
