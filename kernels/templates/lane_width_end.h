/* Closes a lane template (templates/lane_width.h): its type names and PC_LANE_W go. */
#undef F
#undef I
#undef U
#undef V3
#undef convert_F
#undef convert_I
#undef as_F
#undef as_I
#undef as_U
#undef PC_LANE_W
