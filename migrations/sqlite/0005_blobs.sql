-- Large bytes live in the blob store (object_store); rows keep what finds them.
-- Rows written before this migration keep their bytes in `data`.
ALTER TABLE inputs ADD COLUMN in_blob INTEGER NOT NULL DEFAULT 0;  -- 1: the bytes are the blob jobs/{id}/inputs/{name}
ALTER TABLE inputs ADD COLUMN head BLOB;                           -- their first 8 bytes (format sniffing)
ALTER TABLE checkpoints ADD COLUMN blob TEXT;                       -- the frame's key (NULL: the checkpoint is in `data`)
ALTER TABLE jobs ADD COLUMN results TEXT;                          -- the stored result files (JSON), once written
