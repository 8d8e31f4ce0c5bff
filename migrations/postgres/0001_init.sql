-- Jobs, their uploaded inputs, energy history and checkpoints (PostgreSQL; the
-- same tables as migrations/sqlite, with the lease columns from the start).
CREATE TABLE jobs (
    id               TEXT PRIMARY KEY,
    seq              BIGINT GENERATED ALWAYS AS IDENTITY UNIQUE,
    status           TEXT NOT NULL CHECK (status IN ('accepted', 'running', 'successful', 'failed', 'dismissed')),
    spec             TEXT NOT NULL,
    created_at       TEXT NOT NULL,
    started_at       TEXT,
    finished_at      TEXT,
    message          TEXT,
    stop_reason      TEXT,
    cancel_requested BOOLEAN NOT NULL DEFAULT FALSE,
    iteration        BIGINT,
    time             DOUBLE PRECISION,
    tau              DOUBLE PRECISION,
    energy           DOUBLE PRECISION,
    vertices         BIGINT,
    components       BIGINT,
    lease_owner      TEXT,
    lease_epoch      BIGINT NOT NULL DEFAULT 0,
    lease_expires    BIGINT,
    takeovers        INTEGER NOT NULL DEFAULT 0
);
CREATE INDEX jobs_status_seq ON jobs (status, seq);

CREATE TABLE inputs (
    job_id TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    name   TEXT NOT NULL,
    data   BYTEA NOT NULL,
    PRIMARY KEY (job_id, name)
);

CREATE TABLE history (
    job_id     TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    iteration  BIGINT NOT NULL,
    time       DOUBLE PRECISION NOT NULL,
    tau        DOUBLE PRECISION NOT NULL,
    energy     DOUBLE PRECISION NOT NULL,
    vertices   BIGINT NOT NULL,
    components BIGINT NOT NULL,
    PRIMARY KEY (job_id, iteration)
);

CREATE TABLE checkpoints (
    job_id    TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    iteration BIGINT NOT NULL,
    time      DOUBLE PRECISION NOT NULL,
    data      TEXT NOT NULL,
    PRIMARY KEY (job_id, iteration)
);
