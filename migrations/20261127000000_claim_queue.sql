-- Claims in constant time (issue 35). Two denormalised columns, kept right by triggers, so that
-- the claim query is one walk of one index to its first row instead of a search through every
-- pending job's spec:
--
-- * `jobs.start_from`: a continuation job's predecessor (the spec's `start_from`, NULL for a job
--   that starts from its initial state). Backfilled from the spec; written by `upsert_job.sql`.
--   It replaces the expression index `jobs_start_from` on the JSON.
-- * `sweep_points.claim_rank`: where the row stands in its sweep's queue. NULL: its job cannot be
--   claimed now (not pending, or a continuation job whose predecessor has not ended, or whose
--   predecessor is not in the database). 0: pending and claimable, and some pending
--   continuation job waits for it (a chain's next link: claimed first). 1: pending and
--   claimable otherwise. The claim takes the first row of `sweep_points_claim` for its sweep:
--   ordered by (claim_rank, point, replica), the order the claim query had before.
--
-- The rank is a property of the job (every row of a job shared between sweeps carries the same
-- one), defined once in the view `job_claim_rank`. A job's rank depends on its own status, its
-- predecessor's status and its pending successors, so a change of a job's status (or start_from,
-- or its insertion or deletion) recomputes the rank of the job, of its successors and of its
-- predecessor: a few index lookups per change, whichever statement made it.

ALTER TABLE jobs ADD COLUMN start_from TEXT;
UPDATE jobs SET start_from = json_extract(spec, '$.start_from');
DROP INDEX jobs_start_from;
CREATE INDEX jobs_predecessor ON jobs (start_from) WHERE start_from IS NOT NULL;

CREATE VIEW job_claim_rank AS
SELECT j.id AS id,
       CASE
           WHEN j.status != 'pending' THEN NULL
           WHEN j.start_from IS NOT NULL
                AND NOT EXISTS (SELECT 1 FROM jobs d
                                WHERE d.id = j.start_from AND d.status IN ('done', 'failed'))
               THEN NULL
           WHEN EXISTS (SELECT 1 FROM jobs c
                        WHERE c.start_from = j.id AND c.status = 'pending')
               THEN 0
           ELSE 1
       END AS claim_rank
FROM jobs j;

ALTER TABLE sweep_points ADD COLUMN claim_rank INTEGER;
UPDATE sweep_points SET claim_rank = (SELECT r.claim_rank FROM job_claim_rank r
                                      WHERE r.id = sweep_points.job_id);
CREATE INDEX sweep_points_claim ON sweep_points (sweep_id, claim_rank, point, replica)
    WHERE claim_rank IS NOT NULL;

-- A new point row takes its job's rank.
CREATE TRIGGER sweep_points_rank_on_insert AFTER INSERT ON sweep_points
BEGIN
    UPDATE sweep_points SET claim_rank = (SELECT r.claim_rank FROM job_claim_rank r
                                          WHERE r.id = NEW.job_id)
    WHERE rowid = NEW.rowid;
END;

-- A point row moved to another job (re-keying) takes that job's rank.
CREATE TRIGGER sweep_points_rank_on_rekey AFTER UPDATE OF job_id ON sweep_points
BEGIN
    UPDATE sweep_points SET claim_rank = (SELECT r.claim_rank FROM job_claim_rank r
                                          WHERE r.id = NEW.job_id)
    WHERE rowid = NEW.rowid;
END;

-- A job's status changed: its own rank, its successors' (is their predecessor done?) and its
-- predecessor's (does a pending successor wait for it?).
CREATE TRIGGER jobs_rank_on_status AFTER UPDATE OF status ON jobs
WHEN OLD.status IS NOT NEW.status
BEGIN
    UPDATE sweep_points SET claim_rank = (SELECT r.claim_rank FROM job_claim_rank r
                                          WHERE r.id = sweep_points.job_id)
    WHERE job_id = NEW.id
       OR job_id = NEW.start_from
       OR job_id IN (SELECT c.id FROM jobs c WHERE c.start_from = NEW.id);
END;

-- A job's predecessor changed (a spec rewritten in place): the job, both predecessors.
CREATE TRIGGER jobs_rank_on_start_from AFTER UPDATE OF start_from ON jobs
WHEN OLD.start_from IS NOT NEW.start_from
BEGIN
    UPDATE sweep_points SET claim_rank = (SELECT r.claim_rank FROM job_claim_rank r
                                          WHERE r.id = sweep_points.job_id)
    WHERE job_id = NEW.id
       OR job_id = OLD.start_from
       OR job_id = NEW.start_from;
END;

-- A new job: a pending successor makes its predecessor a chain head; jobs already naming it as
-- their predecessor may now be waiting on it.
CREATE TRIGGER jobs_rank_on_insert AFTER INSERT ON jobs
BEGIN
    UPDATE sweep_points SET claim_rank = (SELECT r.claim_rank FROM job_claim_rank r
                                          WHERE r.id = sweep_points.job_id)
    WHERE job_id = NEW.id
       OR job_id = NEW.start_from
       OR job_id IN (SELECT c.id FROM jobs c WHERE c.start_from = NEW.id);
END;

-- A job deleted (re-keying): its predecessor and its successors lose it.
CREATE TRIGGER jobs_rank_on_delete AFTER DELETE ON jobs
BEGIN
    UPDATE sweep_points SET claim_rank = (SELECT r.claim_rank FROM job_claim_rank r
                                          WHERE r.id = sweep_points.job_id)
    WHERE job_id = OLD.start_from
       OR job_id IN (SELECT c.id FROM jobs c WHERE c.start_from = OLD.id);
END;
