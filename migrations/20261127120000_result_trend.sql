-- The trend state of each result (wetgran_core::observe::trend, docs/observables.md "Run to
-- stationarity"): what the monitored series did over the run. NULL for results stored before
-- it was recorded (their runs were tested window by window only). Set from the observables
-- JSON when the result is inserted (store/sql/insert_result.sql), so reports read a column,
-- not the JSON.
ALTER TABLE results ADD COLUMN trend TEXT
    CHECK (trend IS NULL OR trend IN ('stationary', 'heating', 'cooling', 'coarsening', 'undecided'));
