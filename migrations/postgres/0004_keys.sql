-- API keys (`shapeflow keys`): only a SHA-256 of each key is kept. A job belongs
-- to the key that created it (NULL: created without a key, or by the token).
CREATE TABLE keys (
    name       TEXT PRIMARY KEY,
    hash       TEXT NOT NULL UNIQUE,
    admin      BOOLEAN NOT NULL DEFAULT FALSE,
    max_active BIGINT,
    created_at TEXT NOT NULL,
    revoked_at TEXT
);
ALTER TABLE jobs ADD COLUMN owner TEXT;
CREATE INDEX jobs_owner_seq ON jobs (owner, seq);
