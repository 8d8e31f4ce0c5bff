-- A DELETE marks the job (deleted_at) and its rows go in the background; the
-- bytes a job keeps (stored_bytes) count against its key's max_storage; a task
-- that one node of a cluster at a time does is led through `leaders`.
ALTER TABLE jobs ADD COLUMN deleted_at TEXT;
ALTER TABLE jobs ADD COLUMN stored_bytes INTEGER NOT NULL DEFAULT 0;
CREATE INDEX jobs_deleted ON jobs (deleted_at) WHERE deleted_at IS NOT NULL;
ALTER TABLE keys ADD COLUMN max_storage INTEGER;
CREATE TABLE leaders (
    name    TEXT PRIMARY KEY,
    owner   TEXT NOT NULL,
    expires INTEGER NOT NULL
);
