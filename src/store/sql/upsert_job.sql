-- Inserts a job, or gives an existing one its new spec (same id: other thresholds), with the
-- start mode of its spec (`initial.start`, NULL where left out).
-- ?1: job id, ?2: spec (canonical JSON), ?3: created at, ?4: predecessor job id (the spec's
-- start_from; NULL for none)
INSERT INTO jobs (id, spec, created_at, start_from, start_mode)
VALUES (?1, ?2, ?3, ?4, json_extract(?2, '$.scene.initial.start'))
ON CONFLICT (id) DO UPDATE SET spec = excluded.spec, start_from = excluded.start_from,
    start_mode = excluded.start_mode
