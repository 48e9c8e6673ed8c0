"""Access levels of the panel: viewer (nothing writable), operator (setpoint, mode, acknowledge) and
engineer (parameters, tuning, rule tables).

Passwords are kept only as scrypt hashes: from the configuration file `<data>/hmi-access.toml`
(`engineer = "scrypt$..."`, made with `thermost hmi --hash-password`) or from the environment
(`THERMOST_HMI_ENGINEER_PASSWORD`, hashed at start; the plain text is not kept). Without an operator
password the operator level needs none; without an engineer password the engineer level is off.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import tomllib
from dataclasses import dataclass
from pathlib import Path

VIEWER, OPERATOR, ENGINEER = "viewer", "operator", "engineer"
RANK = {VIEWER: 0, OPERATOR: 1, ENGINEER: 2}
ENV = {OPERATOR: "THERMOST_HMI_OPERATOR_PASSWORD", ENGINEER: "THERMOST_HMI_ENGINEER_PASSWORD"}
CONFIG_NAME = "hmi-access.toml"
SCRYPT_N, SCRYPT_R, SCRYPT_P = 2**14, 8, 1


def hash_password(password: str, salt: bytes | None = None) -> str:
    salt = salt or secrets.token_bytes(16)
    digest = hashlib.scrypt(password.encode(), salt=salt, n=SCRYPT_N, r=SCRYPT_R, p=SCRYPT_P)
    return f"scrypt${SCRYPT_N}${SCRYPT_R}${SCRYPT_P}${salt.hex()}${digest.hex()}"


def verify_password(password: str, stored: str) -> bool:
    try:
        kind, n, r, p, salt, digest = stored.split("$")
        if kind != "scrypt":
            return False
        got = hashlib.scrypt(password.encode(), salt=bytes.fromhex(salt), n=int(n), r=int(r), p=int(p))
    except (ValueError, TypeError):
        return False
    return hmac.compare_digest(got.hex(), digest)


class AccessConfigError(ValueError):
    pass


@dataclass
class Access:
    hashes: dict[str, str]  # level -> scrypt hash (a level missing here: see `needs_password`)

    @staticmethod
    def load(data_dir: Path, env: dict[str, str] | None = None) -> Access:
        env = dict(os.environ) if env is None else env
        hashes: dict[str, str] = {}
        path = data_dir / CONFIG_NAME
        if path.exists():
            try:
                conf = tomllib.loads(path.read_text(encoding="utf-8"))
            except (tomllib.TOMLDecodeError, OSError) as exc:
                raise AccessConfigError(f"{path}: {exc}") from None
            for level in (OPERATOR, ENGINEER):
                value = conf.get(level)
                if value is not None:
                    if not isinstance(value, str) or not value.startswith("scrypt$"):
                        raise AccessConfigError(
                            f"{path}: {level} must be a hash from `thermost hmi --hash-password`")
                    hashes[level] = value
        for level, name in ENV.items():
            if env.get(name):
                hashes[level] = hash_password(env[name])
        return Access(hashes)

    def engineer_enabled(self) -> bool:
        return ENGINEER in self.hashes

    def login(self, level: str, password: str) -> str | None:
        """None on success, else the reason (shown in the page)."""
        if level not in (OPERATOR, ENGINEER):
            return f"unknown level {level!r}"
        stored = self.hashes.get(level)
        if stored is None:
            if level == OPERATOR:
                return None
            return f"the engineer level is off: set {ENV[ENGINEER]} or {CONFIG_NAME} in the data folder"
        return None if verify_password(password, stored) else "wrong password"


def allowed(level: str, needed: str) -> bool:
    return RANK.get(level, 0) >= RANK[needed]
