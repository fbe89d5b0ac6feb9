//! Machine-tool chains of homogeneous transforms, first-order error model, identification (Ch. 3).
