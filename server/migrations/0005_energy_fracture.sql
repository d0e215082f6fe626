-- The fracture energy (energy.csv's `fracture` column, at the end): the part of `dissipated`
-- spent on new crack surface. NULL for rows written before: read back as NaN (null in the API).
ALTER TABLE energy ADD COLUMN fracture REAL;
