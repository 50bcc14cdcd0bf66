-- Continuation chains: a job's predecessor is `start_from` in its spec (`JobSpec::start_from`).
-- The claim query looks jobs up by it (is the predecessor done? does a job have pending
-- successors?); an index on the expression keeps that a lookup, not a scan of every spec.

CREATE INDEX jobs_start_from ON jobs (json_extract(spec, '$.start_from'));
