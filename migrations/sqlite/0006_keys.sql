-- API keys (`shapeflow keys`): only a SHA-256 of each key is kept. A job belongs
-- to the key that created it (NULL: created without a key, or by the token).
CREATE TABLE keys (
    name       TEXT PRIMARY KEY,
    hash       TEXT NOT NULL UNIQUE,
    admin      INTEGER NOT NULL DEFAULT 0,
    max_active INTEGER,
    created_at TEXT NOT NULL,
    revoked_at TEXT
);
ALTER TABLE jobs ADD COLUMN owner TEXT;
CREATE INDEX jobs_owner_seq ON jobs (owner, seq);
