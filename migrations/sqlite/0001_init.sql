-- Jobs, their energy history and checkpoints.
CREATE TABLE jobs (
    id               TEXT PRIMARY KEY,
    seq              INTEGER NOT NULL UNIQUE,
    status           TEXT NOT NULL CHECK (status IN ('accepted', 'running', 'successful', 'failed', 'dismissed')),
    spec             TEXT NOT NULL,
    created_at       TEXT NOT NULL,
    started_at       TEXT,
    finished_at      TEXT,
    message          TEXT,
    stop_reason      TEXT,
    cancel_requested INTEGER NOT NULL DEFAULT 0,
    iteration        INTEGER,
    time             REAL,
    tau              REAL,
    energy           REAL,
    vertices         INTEGER,
    components       INTEGER
);
CREATE INDEX jobs_status_seq ON jobs (status, seq);

CREATE TABLE history (
    job_id     TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    iteration  INTEGER NOT NULL,
    time       REAL NOT NULL,
    tau        REAL NOT NULL,
    energy     REAL NOT NULL,
    vertices   INTEGER NOT NULL,
    components INTEGER NOT NULL,
    PRIMARY KEY (job_id, iteration)
);

CREATE TABLE checkpoints (
    job_id    TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    iteration INTEGER NOT NULL,
    time      REAL NOT NULL,
    data      TEXT NOT NULL,
    PRIMARY KEY (job_id, iteration)
);
