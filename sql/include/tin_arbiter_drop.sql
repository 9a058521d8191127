-- sql/include/tin_arbiter_drop.sql: what sql/include/tin_arbiter.sql made.
DROP TABLE tdc_arb_q, tdc_arb_t, tdc_arb_s;
DROP FUNCTION tdc_arb_num(float8), tdc_arb_num_bits(float8), tdc_arb_orient(numeric, numeric, numeric, numeric, numeric, numeric),
	tdc_arb_incircle(numeric, numeric, numeric, numeric, numeric, numeric, numeric, numeric),
	tdc_arb_div(numeric, numeric), tdc_arb_samples(geometry), tdc_arb_triangles(geometry, bool),
	tdc_arb_queries(geometry), tdc_arb_locate(numeric, numeric), tdc_arb_circle(bigint),
	tdc_arb_value(bigint, numeric, numeric), tdc_arb_nearest(), tdc_arb_linear();
