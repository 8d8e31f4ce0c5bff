-- Large bytes live in the blob store (object_store); rows keep what finds them.
ALTER TABLE inputs ADD COLUMN in_blob BOOLEAN NOT NULL DEFAULT FALSE;  -- the bytes are the blob jobs/{id}/inputs/{name}
ALTER TABLE inputs ADD COLUMN head BYTEA;                              -- their first 8 bytes (format sniffing)
ALTER TABLE checkpoints ADD COLUMN blob TEXT;                           -- the frame's key (NULL: the checkpoint is in `data`)
ALTER TABLE jobs ADD COLUMN results TEXT;                              -- the stored result files (JSON), once written
