-- The verdict on each result's label (wetgran_core::observe::settling::Verdict): stationary,
-- label_kept or not_settled, the one answer to "did this run settle?". It depends on the label
-- (what may still drift depends on the phase), so it is written with the label: at insert
-- (store/sql/insert_result.sql) and whenever the label changes (store/sql/set_result_label.sql).
-- Results stored before it have NULL: they were measured under an older run policy and are
-- outdated. The covering index of the reports holds it in place of `converged`, which nothing
-- writes any more.
ALTER TABLE results ADD COLUMN verdict TEXT
    CHECK (verdict IS NULL OR verdict IN ('stationary', 'label_kept', 'not_settled'));

DROP INDEX results_report;
CREATE INDEX results_report ON results (job_id, phase, wall_seconds, trend, verdict);
