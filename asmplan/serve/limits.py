"""The service's bounds, in a module of their own so the command line reads them without
loading the service."""

DEFAULT_MAX_SESSIONS = 10_000
"""Most sessions open at once (``asmplan serve --max-sessions``; one more is refused, 429)."""
DEFAULT_TTL = 24 * 3600.0
"""Seconds without an event after which an open session ages out (``--session-ttl``)."""
DEFAULT_MAX_DB_MB = 1024
"""Largest size of the sessions database, MB (``--max-db-mb``; past it a change is refused
with 503, nothing changed)."""
