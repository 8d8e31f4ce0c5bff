-- Claims look only at jobs that can still run: an index of those by submission
-- order, so that a claim does not scan the finished jobs.
CREATE INDEX jobs_open_seq ON jobs (seq) WHERE status IN ('accepted', 'running');
