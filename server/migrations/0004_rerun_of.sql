-- The job a rerun was made from (`POST /api/v1/jobs/{id}/rerun`); NULL for other jobs. Not a
-- foreign key: the original may be deleted while its reruns stay.
ALTER TABLE jobs ADD COLUMN rerun_of TEXT;
